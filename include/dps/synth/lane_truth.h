// dps — the lanes' ground truth of a synthetic drive (truth_lanes.csv, truth_ego_lane.csv; the
// formats in util/lanes_csv.h), from the scene's road: straight lane lines along the world's Z
// axis at the ego lane's centre +- half a lane width and every lane width beyond (the road's
// outer lines solid, the others dashed), seen from the vehicle's pose at each frame.
#pragma once

#include <vector>

#include "dps/synth/scene.h"
#include "dps/util/lanes_csv.h"

namespace dps {

struct LaneTruth {
  std::vector<LaneBoundaryRow> boundaries;  // per frame: left2, left, right, right2 where the road has them
  std::vector<EgoLaneRow> ego;              // per frame, while the vehicle's centre is on the road
};

// Every frame's lane truth (empty for a scene without road markings).
LaneTruth LaneTruthOf(const Scene& scene);

}  // namespace dps
