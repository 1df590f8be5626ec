// Tests of dps::CameraModel: hand-computed pixels, round trips over dense grids with random
// parameters, validity at the edges, the hyperbolic <-> unified conversion, the paper's eq. 4,
// and agreement with cv::fisheye::projectPoints.
#include <cmath>
#include <random>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "check.h"
#include "dps/camera/camera_model.h"

namespace {

constexpr double kRoundTripTolPx = 1e-6;
constexpr double kRayTol = 1e-9;
constexpr double kOpenCVTolPx = 1e-6;
constexpr double kPi = 3.14159265358979323846;

Eigen::Matrix3d MakeK(double fx, double fy, double cx, double cy, double skew = 0.0) {
  Eigen::Matrix3d K;
  K << fx, skew, cx, 0, fy, cy, 0, 0, 1;
  return K;
}

std::mt19937 rng(42);
double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

// Random models of every type, with parameters in the ranges real cameras have.
std::vector<dps::CameraModel> RandomModels(int per_type) {
  std::vector<dps::CameraModel> out;
  for (int i = 0; i < per_type; ++i) {
    const int w = 640, h = 480;
    const Eigen::Matrix3d K = MakeK(Uniform(100, 400), Uniform(100, 400), Uniform(300, 340),
                                    Uniform(220, 260), Uniform(-0.5, 0.5));
    // Hyperbolic mirrors with a^2 - b^2 both above and below 1, and b > a (xi > 1).
    out.push_back(dps::CameraModel::Hyperbolic(w, h, K, Uniform(0.5, 2.0), Uniform(0.0, 2.5)));
    out.push_back(dps::CameraModel::Unified(w, h, K, Uniform(0.0, 1.6), Uniform(150, 400)));
    out.push_back(dps::CameraModel::Fisheye(
        w, h, K, {Uniform(-0.05, 0.05), Uniform(-0.02, 0.02), Uniform(-0.01, 0.01),
                  Uniform(-0.003, 0.003)}));
  }
  return out;
}

void TestHandComputedPixels() {
  // Paper eq. 3 by hand: K = [100 0 320; 0 100 240; 0 0 1], a = 2, b = 1.
  const auto m = dps::CameraModel::Hyperbolic(640, 480, MakeK(100, 100, 320, 240), 2.0, 1.0);
  Eigen::Vector2d px;
  CHECK(m.Project({1, 0, 0}, &px));  // r = 1, a Z + b r = 1
  CHECK_NEAR(px.x(), 420.0, 1e-12);
  CHECK_NEAR(px.y(), 240.0, 1e-12);
  CHECK(m.Project({3, 0, 4}, &px));  // r = 5, a Z + b r = 13
  CHECK_NEAR(px.x(), 320.0 + 300.0 / 13.0, 1e-12);
  CHECK(m.Project({0, -2, 0}, &px));  // r = 2, a Z + b r = 2
  CHECK_NEAR(px.y(), 240.0 - 100.0, 1e-12);
  CHECK(m.Project({0, 0, 7}, &px));  // the mirror axis lands on the principal point
  CHECK_NEAR(px.x(), 320.0, 1e-12);
  CHECK_NEAR(px.y(), 240.0, 1e-12);

  // Equidistant fisheye: radius = f * theta.
  const auto f = dps::CameraModel::Fisheye(640, 480, MakeK(200, 200, 320, 240), {0, 0, 0, 0});
  CHECK(f.Project({1, 0, 0}, &px));  // theta = 90 degrees
  CHECK_NEAR(px.x(), 320.0 + 200.0 * kPi / 2.0, 1e-9);
  CHECK(f.Project({0, 1, -1}, &px));  // theta = 135 degrees: beyond a pinhole, fine for a fisheye
  CHECK_NEAR(px.y(), 240.0 + 200.0 * 0.75 * kPi, 1e-9);
  Eigen::Vector3d ray;
  CHECK(f.Unproject({320.0 + 200.0 * kPi / 4.0, 240.0}, &ray));
  CHECK_NEAR(ray.x(), std::sqrt(0.5), kRayTol);
  CHECK_NEAR(ray.z(), std::sqrt(0.5), kRayTol);
}

void TestRoundTrips() {
  int valid_pixels = 0;
  int models = 0;
  for (const dps::CameraModel& m : RandomModels(8)) {
    ++models;
    double worst_px = 0.0;
    double worst_ray = 0.0;
    for (int v = 0; v < m.height(); v += 4) {
      for (int u = 0; u < m.width(); u += 4) {
        const Eigen::Vector2d px(u + 0.25, v + 0.75);
        Eigen::Vector3d ray;
        if (!m.Unproject(px, &ray)) continue;
        ++valid_pixels;
        CHECK_NEAR(ray.norm(), 1.0, 1e-12);
        Eigen::Vector2d back;
        const bool ok = m.Project(ray * Uniform(0.1, 100.0), &back);
        CHECK(ok);
        if (!ok) continue;
        worst_px = std::max(worst_px, (back - px).norm());
        Eigen::Vector3d ray2;
        CHECK(m.Unproject(back, &ray2));
        worst_ray = std::max(worst_ray, (ray2 - ray).norm());
      }
    }
    CHECK_NEAR(worst_px, 0.0, kRoundTripTolPx);
    CHECK_NEAR(worst_ray, 0.0, kRayTol);
  }
  CHECK(valid_pixels > models * 1000);  // the grid really exercised the models
}

void TestValidity() {
  Eigen::Vector2d px;
  Eigen::Vector3d ray;
  // a > b (xi < 1): rays valid iff a Z + b r > 0, i.e. cos(theta) > -b/a.
  const auto h = dps::CameraModel::Hyperbolic(640, 480, MakeK(150, 150, 320, 240), 1.25, 0.75);
  CHECK(!h.Project({0, 0, 0}, &px));                   // the viewpoint itself
  CHECK(!h.Project({0, 0, -1}, &px));                  // straight behind the mirror
  const double edge = std::acos(-0.75 / 1.25);
  CHECK(h.Project({std::sin(edge - 1e-3), 0, std::cos(edge - 1e-3)}, &px));
  CHECK(!h.Project({std::sin(edge + 1e-3), 0, std::cos(edge + 1e-3)}, &px));
  CHECK_NEAR(h.max_theta_rad(), edge, 1e-12);

  // b > a (xi > 1): pixels beyond a circle have no real root; the far sheet is rejected.
  const auto u = dps::CameraModel::Unified(640, 480, MakeK(100, 100, 320, 240), 1.5);
  const double rho_max = 1.0 / std::sqrt(1.5 * 1.5 - 1.0);  // disc = 1 + rho^2 (1 - xi^2) = 0
  CHECK(u.Unproject({320 + 100 * rho_max * 0.999, 240}, &ray));
  CHECK(!u.Unproject({320 + 100 * rho_max * 1.001, 240}, &ray));
  CHECK(!u.Project({0, 0, -1}, &px));
  const double far = std::acos(-1.0 / 1.5);
  CHECK(!u.Project({std::sin(far + 1e-3), 0, std::cos(far + 1e-3)}, &px));

  // Rim: pixels farther than rim_radius_px from (cx, cy) see nothing, and no point lands there.
  const auto r = dps::CameraModel::Unified(640, 480, MakeK(150, 150, 320, 240), 0.9, 200.0);
  CHECK(r.Unproject({320 + 199.0, 240}, &ray));
  CHECK(!r.Unproject({320 + 201.0, 240}, &ray));
  CHECK(!r.Project({0.866, 0, -0.5}, &px));  // 30 deg above the horizon: lands at 325 px > 200

  // Fisheye: rays beyond the lens' monotonic range are invalid.
  const auto f =
      dps::CameraModel::Fisheye(640, 480, MakeK(200, 200, 320, 240), {0.0, -0.05, 0.0, 0.0});
  // d theta_d / d theta = 1 - 0.25 theta^4 vanishes at theta = sqrt(2).
  CHECK_NEAR(f.max_theta_rad(), std::sqrt(2.0), 1e-3);
  CHECK(f.Project({std::sin(1.3), 0, std::cos(1.3)}, &px));
  CHECK(!f.Project({std::sin(1.5), 0, std::cos(1.5)}, &px));
  CHECK(!f.Unproject({320 + 200 * 1.2, 240}, &ray));  // theta_d(sqrt 2) ~ 1.131
  CHECK(f.InImage({0, 0}) && !f.InImage({640, 10}) && !f.InImage({-0.6, 10}));
}

void TestHyperbolicUnifiedConversion() {
  for (int i = 0; i < 20; ++i) {
    const Eigen::Matrix3d K = MakeK(Uniform(100, 300), Uniform(100, 300), 320, 240, 0.1);
    const auto h = dps::CameraModel::Hyperbolic(640, 480, K, Uniform(0.5, 2), Uniform(0, 1.5));
    const auto u = dps::HyperbolicToUnified(h);
    CHECK_NEAR(u.xi(), h.b() / h.a(), 1e-15);
    const auto h2 = dps::UnifiedToHyperbolic(u, h.a());
    CHECK_NEAR((h2.K() - h.K()).norm(), 0.0, 1e-9);
    CHECK_NEAR(h2.b(), h.b(), 1e-12);
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector3d p(Uniform(-5, 5), Uniform(-5, 5), Uniform(-5, 5));
      Eigen::Vector2d ph, pu;
      const bool vh = h.Project(p, &ph);
      const bool vu = u.Project(p, &pu);
      CHECK_EQ(vh, vu);
      if (vh && vu) CHECK_NEAR((ph - pu).norm(), 0.0, 1e-9);
    }
  }
}

void TestPaperEq4() {
  // When a^2 - b^2 = 1 the paper's inverse equals the general one.
  for (int i = 0; i < 10; ++i) {
    const double b = Uniform(0.2, 1.5);
    const double a = std::sqrt(1.0 + b * b);
    const auto m = dps::CameraModel::Hyperbolic(640, 480, MakeK(120, 130, 320, 240), a, b);
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector2d px(Uniform(0, 640), Uniform(0, 480));
      Eigen::Vector3d ray;
      if (!m.Unproject(px, &ray)) continue;
      CHECK_NEAR((dps::PaperEq4Ray(m, px) - ray).norm(), 0.0, 1e-12);
    }
  }
  // When it does not hold, eq. 4 is off: the general inverse is needed.
  const auto m = dps::CameraModel::Hyperbolic(640, 480, MakeK(120, 120, 320, 240), 1.3, 0.4);
  Eigen::Vector3d ray;
  CHECK(m.Unproject({500, 300}, &ray));
  CHECK((dps::PaperEq4Ray(m, {500, 300}) - ray).norm() > 1e-3);
}

void TestFisheyeAgainstOpenCV() {
  for (int i = 0; i < 10; ++i) {
    const double fx = Uniform(150, 400), fy = Uniform(150, 400), alpha = Uniform(-0.01, 0.01);
    const Eigen::Matrix3d K = MakeK(fx, fy, Uniform(300, 340), Uniform(220, 260), alpha * fx);
    const std::array<double, 4> d{Uniform(-0.05, 0.05), Uniform(-0.02, 0.02),
                                  Uniform(-0.01, 0.01), Uniform(-0.003, 0.003)};
    const auto m = dps::CameraModel::Fisheye(640, 480, K, d);
    std::vector<cv::Point3d> pts;
    for (int k = 0; k < 300; ++k) pts.emplace_back(Uniform(-3, 3), Uniform(-3, 3), Uniform(0.05, 5));
    const cv::Matx33d Kcv(K(0, 0), K(0, 1), K(0, 2), 0, K(1, 1), K(1, 2), 0, 0, 1);
    std::vector<cv::Point2d> ref;
    cv::fisheye::projectPoints(pts, ref, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), Kcv,
                               cv::Vec4d(d[0], d[1], d[2], d[3]), alpha);
    for (size_t k = 0; k < pts.size(); ++k) {
      Eigen::Vector2d px;
      const Eigen::Vector3d p(pts[k].x, pts[k].y, pts[k].z);
      if (std::atan2(std::hypot(p.x(), p.y()), p.z()) > m.max_theta_rad()) continue;
      CHECK(m.Project(p, &px));
      CHECK_NEAR(px.x(), ref[k].x, kOpenCVTolPx);
      CHECK_NEAR(px.y(), ref[k].y, kOpenCVTolPx);
    }
  }
}

void TestBadParameters() {
  const Eigen::Matrix3d K = MakeK(100, 100, 320, 240);
  CHECK_THROWS_WITH(dps::CameraModel::Hyperbolic(0, 480, K, 1, 0.5), std::invalid_argument,
                    "width");
  CHECK_THROWS_WITH(dps::CameraModel::Hyperbolic(640, 480, K, -1, 0.5), std::invalid_argument,
                    "'a'");
  CHECK_THROWS_WITH(dps::CameraModel::Hyperbolic(640, 480, K, 1, -0.5), std::invalid_argument,
                    "'b'");
  CHECK_THROWS_WITH(dps::CameraModel::Unified(640, 480, MakeK(-100, 100, 320, 240), 0.5),
                    std::invalid_argument, "0 < fx <=");
  CHECK_THROWS_WITH(dps::CameraModel::Unified(640, 480, K, -0.1), std::invalid_argument, "xi");
  CHECK_THROWS_WITH(dps::CameraModel::Fisheye(640, 480, K, {-0.5, 0, 0, 0}), std::invalid_argument,
                    "k1");
  Eigen::Matrix3d bad = K;
  bad(2, 0) = 0.1;
  CHECK_THROWS_WITH(dps::CameraModel::Unified(640, 480, bad, 0.5), std::invalid_argument,
                    "K[2][0]");
  CHECK_THROWS_WITH(dps::HyperbolicToUnified(dps::CameraModel::Unified(640, 480, K, 0.5)),
                    std::invalid_argument, "unified");
  CHECK_THROWS_WITH(dps::ModelTypeFromName("pinhole"), std::invalid_argument, "pinhole");
}

}  // namespace

int main() {
  TestHandComputedPixels();
  TestRoundTrips();
  TestValidity();
  TestHyperbolicUnifiedConversion();
  TestPaperEq4();
  TestFisheyeAgainstOpenCV();
  TestBadParameters();
  return dps_test::Report();
}
