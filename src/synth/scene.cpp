#include "dps/synth/scene.h"

#include <algorithm>
#include <cmath>

namespace dps {

int Scene::FrameCount() const {
  return std::max(1, static_cast<int>(std::lround(duration_s * fps)));
}

void ResizeScene(Scene* scene, int width, int height) {
  for (RigCamera& c : scene->rig.cameras) c.model = ResizeCameraModel(c.model, width, height);
}

}  // namespace dps
