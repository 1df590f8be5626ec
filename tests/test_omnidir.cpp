// The unified model with distortion against cv::omnidir (opencv_contrib's ccalib, used by this test
// only): projection and undistortion agree on points over the valid field, for real-looking
// calibrations (KITTI-360's side fisheyes are MEI models with k1, k2, p1, p2).
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <opencv2/ccalib/omnidir.hpp>

#include "check.h"
#include "dps/camera/camera_model.h"

namespace {

constexpr double kPixelTol = 1e-6;  // px
constexpr double kRayTol = 1e-6;    // rad

std::mt19937 rng(7);
double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

void TestAgainstOmnidir() {
  double worst_px = 0, worst_rad = 0;
  int compared = 0;
  for (int i = 0; i < 12; ++i) {
    const double xi = Uniform(0.8, 2.2);
    const double fx = Uniform(300, 1400), fy = fx * Uniform(0.98, 1.02), s = Uniform(-0.5, 0.5);
    Eigen::Matrix3d K;
    K << fx, s, Uniform(620, 720), 0, fy, Uniform(680, 720), 0, 0, 1;
    const std::array<double, 4> d{Uniform(-0.3, 0.1), Uniform(-0.05, 0.3), Uniform(-0.002, 0.002),
                                  Uniform(-0.002, 0.002)};
    const dps::CameraModel m = dps::CameraModel::Unified(1400, 1400, K, xi, 0.0, d);
    const cv::Matx33d Kcv(K(0, 0), K(0, 1), K(0, 2), 0, K(1, 1), K(1, 2), 0, 0, 1);
    const cv::Matx14d Dcv(d[0], d[1], d[2], d[3]);
    // Rays on a grid of directions up to 95 degrees off the axis, those the model accepts.
    std::vector<cv::Point3d> rays;
    for (double theta = 0.0; theta <= 95.0 * M_PI / 180.0; theta += M_PI / 90.0) {
      for (double phi = 0.0; phi < 2 * M_PI; phi += M_PI / 18.0) {
        const Eigen::Vector3d r(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        Eigen::Vector2d px;
        if (m.Project(r, &px)) rays.emplace_back(r.x(), r.y(), r.z());
      }
    }
    CHECK(rays.size() > 100);
    std::vector<cv::Point2d> ref;
    cv::omnidir::projectPoints(rays, ref, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), Kcv, xi, Dcv);
    // cv::omnidir::undistortPoints with R = I and K' = I gives the ray's point on the unit sphere's
    // normalised plane x / z (perspective), which is enough to compare directions in front.
    std::vector<cv::Point2d> undistorted;
    cv::omnidir::undistortPoints(ref, undistorted, Kcv, Dcv, cv::Mat(cv::Matx<double, 1, 1>(xi)), cv::Matx33d::eye());
    for (size_t k = 0; k < rays.size(); ++k) {
      Eigen::Vector2d px;
      const Eigen::Vector3d r(rays[k].x, rays[k].y, rays[k].z);
      m.Project(r, &px);
      const double e_px = std::hypot(px.x() - ref[k].x, px.y() - ref[k].y);
      worst_px = std::max(worst_px, e_px);
      CHECK(e_px <= kPixelTol);
      Eigen::Vector3d back;
      CHECK(m.Unproject(px, &back));
      const double e_rad = std::acos(std::min(1.0, back.dot(r)));
      worst_rad = std::max(worst_rad, e_rad);
      CHECK(e_rad <= kRayTol);
      if (r.z() > 0.2) {  // the perspective point of OpenCV's undistortion, in front only
        const Eigen::Vector3d u(undistorted[k].x, undistorted[k].y, 1.0);
        CHECK(std::acos(std::min(1.0, u.normalized().dot(back))) <= kRayTol);
      }
      ++compared;
    }
  }
  std::printf("unified with distortion vs cv::omnidir: %d rays, worst %.2e px, round trip worst %.2e rad\n", compared,
              worst_px, worst_rad);
}

// Where the radial distortion folds back, the model sees nothing rather than a wrong ray.
void TestValidity() {
  Eigen::Matrix3d K;
  K << 500, 0, 640, 0, 500, 480, 0, 0, 1;
  const dps::CameraModel m = dps::CameraModel::Unified(1280, 960, K, 1.0, 0.0, {-0.3, 0.0, 0.0, 0.0});
  // r (1 - 0.3 r^2) grows up to r = 1 / sqrt(0.9): beyond, projection refuses.
  Eigen::Vector2d px;
  const double r_turn = 1.0 / std::sqrt(0.9);
  // A ray whose normalised radius x / (z + 1) is 0.99 r_turn, and one at 1.01 r_turn.
  for (const double f : {0.99, 1.01}) {
    const double r = f * r_turn;
    // x / (z + xi) = r on the unit sphere with xi = 1: theta = 2 atan(r).
    const double theta = 2.0 * std::atan(r);
    const bool ok = m.Project(Eigen::Vector3d(std::sin(theta), 0, std::cos(theta)), &px);
    CHECK_EQ(ok, f < 1.0);
  }
  CHECK_THROWS_WITH(dps::CameraModel::Unified(640, 480, K, 1.0, 0.0, {0, 0, std::nan(""), 0}), std::invalid_argument,
                    "p1");
}

}  // namespace

int main() {
  TestAgainstOmnidir();
  TestValidity();
  return dps_test::Report();
}
