// Uses the installed dps: builds a camera, projects a point and unprojects it again.
#include <cstdio>

#include "dps/camera/camera_model.h"

int main() {
  Eigen::Matrix3d K;
  K << 150, 0, 320, 0, 150, 240, 0, 0, 1;
  const auto camera = dps::CameraModel::Hyperbolic(640, 480, K, 1.2, 0.66);
  Eigen::Vector2d pixel;
  Eigen::Vector3d ray;
  if (!camera.Project({1.0, 0.5, 0.2}, &pixel) || !camera.Unproject(pixel, &ray)) return 1;
  const double error = (ray - Eigen::Vector3d(1.0, 0.5, 0.2).normalized()).norm();
  std::printf("consumer: pixel (%.3f, %.3f), ray error %.2e\n", pixel.x(), pixel.y(), error);
  return error < 1e-9 ? 0 : 1;
}
