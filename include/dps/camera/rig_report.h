// dps — looking at a rig: a text summary of each camera, a picture of what the cameras see of
// the road around the car, and the rig's geometry drawn over a camera's own image (`dps-rig show`,
// `dps-rig check`). The quickest test that a calibration and a mounting make sense.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/rig.h"
#include "dps/util/lanes_csv.h"

namespace dps {

// One line per camera: model, image size, field of view (largest angle from the axis), position
// and height above the road, where the axis points (azimuth from straight ahead, positive to the
// right; elevation, negative below the horizon), and the share of the road within `range_m` of the
// car that it sees.
std::string RigSummary(const Rig& rig, double range_m = 10.0);

// A top-down picture (X right, Z up the page) of the road within range_m of the vehicle origin at
// px_per_m: each camera's footprint on the road (pixels whose ground point it sees, in its image
// and mask) tinted and outlined in its own colour, the own car as a rectangle, the cameras as dots, 1 m grid lines and
// a legend.
cv::Mat DrawRigFootprints(const Rig& rig, double range_m = 12.0, double px_per_m = 40.0);

// The rig's geometry over one camera's image (BGR or grey, the model's size): the outline of the
// valid field (green), the horizon (yellow), a road grid every grid_m metres within range_m
// (cyan) and the own car's outline on the road (red).
cv::Mat DrawRigCheck(const RigCamera& camera, const Vehicle& vehicle, const cv::Mat& image,
                     double range_m = 20.0, double grid_m = 1.0);

// Lane boundaries (lanes.csv's rows: x = offset + tan(heading) z + curvature z^2 / 2 on the road,
// vehicle frame) over one camera's image (BGR, the model's size), within range_m of the vehicle
// origin along the car, in magenta, each named (left, right, ...) beside its nearest point the
// camera sees.
void DrawLaneBoundaries(const RigCamera& camera, const std::vector<LaneBoundaryRow>& boundaries, double range_m,
                        cv::Mat* image);

}  // namespace dps
