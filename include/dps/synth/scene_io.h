// dps — reading scene description files for dps-synth (format: docs/synth.md).
#pragma once

#include <string>

#include "dps/synth/scene.h"

namespace dps {

// Reads and validates a scene file (cv::FileStorage YAML). A `rig:` given as a path is read
// relative to the scene file's folder. Throws dps::Error with a one-line message naming the file
// and the field (e.g. "scene.yaml: objects[2]: field 'length' = -1: violated constraint > 0").
Scene ReadScene(const std::string& path);

}  // namespace dps
