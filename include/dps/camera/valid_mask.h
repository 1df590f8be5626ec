// dps — which pixels of a camera see the world.
//
// A camera's valid pixels are those its model can unproject (inside its domain and its rim) and
// that its mask, when it has one, marks 255. The mask says what the model cannot: where a mirror's
// or lens's field really ends, and the own car. It comes from rig.yaml (`mask:`), from the drive
// (`masks/<camera>.png`), or is estimated from the drive's images (EstimateFieldMask): the area
// beyond the field receives no light, so it stays dark in every frame while the scene changes.
// Every view built from the camera inherits its validity (virtual_view.h), and no stereo match
// uses a window touching an invalid pixel (sad_stereo.h).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/rig.h"

namespace dps {

// CV_8U of the model's image size: 255 where the pixel centre unprojects to a ray (inside the
// model's domain and rim); else 0.
cv::Mat ModelValidMask(const CameraModel& model);

// ModelValidMask where the camera's mask (when set) is 255 too.
cv::Mat CameraValidMask(const RigCamera& camera);

// Reads a mask image for `model`: 8-bit, the model's size; pixels > 127 become 255, the others 0.
// Throws dps::Error naming the file when it is unreadable or of another size.
cv::Mat ReadCameraMask(const std::string& path, const CameraModel& model);

struct FieldMaskOptions {
  // A pixel is dark when it never gets brighter than this fraction of the scene's brightness (the
  // 75th percentile of the brightest value each pixel reaches, over the pixels the model can
  // see). In (0, 1).
  double dark_fraction = 0.15;
  // The field's edge is soft (blur, anti-aliasing, compression): the invalid area grows by this
  // fraction of the image width (at least one pixel). In [0, 0.1].
  double edge_margin_fraction = 0.005;

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// The mask of what lies beyond the camera's field, from frames of one camera (grey or BGR, the
// model's size; more frames while the car moves tell dark things from the dark beyond the field):
// the pixels that stay dark in every frame and are connected to the image's border or to what the
// model cannot see, grown by the edge margin. 255 = sees the world. Throws dps::Error when there
// are no frames or their size differs from the model's.
cv::Mat EstimateFieldMask(const std::vector<cv::Mat>& frames, const CameraModel& model,
                          const FieldMaskOptions& options = FieldMaskOptions());

}  // namespace dps
