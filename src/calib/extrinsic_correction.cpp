#include "dps/calib/extrinsic_correction.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "dps/camera/box.h"
#include "dps/camera/valid_mask.h"
#include "dps/util/error.h"
#include "dps/util/image.h"
#include "dps/util/math.h"

namespace dps {
namespace {

constexpr int kWindow = 21;  // Lucas-Kanade's window, px
constexpr double kStartScalePx = 4.0;  // the robust weights' first scale
constexpr int kWarpStep = 4;  // px between the rays computed exactly (RoadRegion, RoadWarp)

Eigen::Matrix3d RotationFromVector(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  return angle > 0 ? AxisAngle(w / angle, angle) : Eigen::Matrix3d::Identity();
}

// The pixels where a road feature may be taken: the ray meets the road between the distances,
// outside the vehicle's footprint and margin, and every pixel of the tracking window around it sees
// the road (the camera's valid pixels, not the own car; no ray through the vehicle's body below
// the camera's level): a window that holds the own car's or the field's edge tracks that edge.
//
// The rays are classified every kWarpStep pixels (the classes' edges are smooth curves in the
// image); the valid pixels and the own car at every pixel.
cv::Mat RoadRegion(const RigCamera& camera, const cv::Mat& valid, const Vehicle& vehicle, const ExtrinsicCorrectionOptions& o) {
  const cv::Size coarse_size(valid.cols / kWarpStep + 2, valid.rows / kWarpStep + 2);
  cv::Mat road(coarse_size, CV_8U, cv::Scalar(0)), region(coarse_size, CV_8U, cv::Scalar(0));
  const Eigen::Vector3d& t = camera.vehicle_from_camera.t;
  const double half_width = vehicle.width_m / 2 + o.vehicle_margin_m, half_length = vehicle.length_m / 2 + o.vehicle_margin_m;
  // The body up to the camera's level (the camera itself outside it, in its mirror).
  const Eigen::Vector3d lo(-vehicle.width_m / 2, std::min(t.y(), 0.0), -vehicle.length_m / 2);
  const Eigen::Vector3d hi(vehicle.width_m / 2, 0.0, vehicle.length_m / 2);
  for (int r = 0; r < coarse_size.height; ++r) {
    for (int c = 0; c < coarse_size.width; ++c) {
      Eigen::Vector3d ray, ground;
      if (!camera.model.Unproject({c * kWarpStep, r * kWarpStep}, &ray) ||
          !RayMeetsRoad(t, camera.vehicle_from_camera.Rotate(ray), &ground) ||
          RayMeetsBox(t, ground - t, lo, hi, 0.1 / (ground - t).norm(), 1.0)) {
        continue;
      }
      road.at<std::uint8_t>(r, c) = 255;
      const double distance = std::hypot(ground.x() - t.x(), ground.z() - t.z());
      if (distance < o.min_distance_m || distance > o.max_distance_m) continue;
      if (std::abs(ground.x()) <= half_width && std::abs(ground.z()) <= half_length) continue;
      region.at<std::uint8_t>(r, c) = 255;
    }
  }
  // Back to pixels (each coarse sample stands for the pixels up to half a step around it).
  const auto full = [&](const cv::Mat& coarse) {
    cv::Mat big;
    cv::resize(coarse, big, cv::Size(coarse.cols * kWarpStep, coarse.rows * kWarpStep), 0, 0, cv::INTER_NEAREST);
    const int shift = kWarpStep / 2;
    return cv::Mat(big(cv::Rect(shift, shift, valid.cols, valid.rows)).clone());
  };
  cv::Mat sees = full(road) & valid;
  if (!camera.own_car.empty()) sees &= ~camera.own_car;
  // The window's margin, and the coarse edges' half step.
  cv::erode(sees, sees, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(kWindow + 2 + kWarpStep, kWindow + 2 + kWarpStep)));
  return full(region) & sees;
}

// Where the road seen at `pixel` of one frame appears in another, `other_from_this` apart (the
// rig as it is); false when the pixel does not see the road or the other frame has no pixel for it.
bool RoadPixel(const RigCamera& camera, const Pose& other_from_this, const Eigen::Vector2d& pixel, Eigen::Vector2d* other) {
  const Pose& c = camera.vehicle_from_camera;
  Eigen::Vector3d ray, ground;
  return camera.model.Unproject(pixel, &ray) && RayMeetsRoad(c.t, c.Rotate(ray), &ground) &&
         camera.model.Project(c.R.transpose() * (other_from_this.Apply(ground) - c.t), other);
}

// A remap of another frame onto the pixels `roi` of this one through the road plane (CV_32FC2 of
// the roi's size, far outside the image where there is none), computed every kWarpStep pixels and
// interpolated between (the warp is smooth): samples at the pixels that cv::resize's linear
// interpolation by kWarpStep puts its source samples at.
cv::Mat RoadWarp(const RigCamera& camera, const Pose& other_from_this, const cv::Rect& roi) {
  cv::Mat coarse(roi.height / kWarpStep + 2, roi.width / kWarpStep + 2, CV_32FC2);
  const double offset = (kWarpStep - 1) / 2.0;
  for (int r = 0; r < coarse.rows; ++r) {
    for (int c = 0; c < coarse.cols; ++c) {
      Eigen::Vector2d other;
      const bool ok = RoadPixel(camera, other_from_this, {roi.x + c * kWarpStep + offset, roi.y + r * kWarpStep + offset}, &other);
      coarse.at<cv::Vec2f>(r, c) = ok ? cv::Vec2f(static_cast<float>(other.x()), static_cast<float>(other.y())) : cv::Vec2f(-1e4f, -1e4f);
    }
  }
  cv::Mat map;
  cv::resize(coarse, map, cv::Size(coarse.cols * kWarpStep, coarse.rows * kWarpStep), 0, 0, cv::INTER_LINEAR);
  return map(cv::Rect(0, 0, roi.width, roi.height)).clone();
}

// The smaller eigenvalue of the image's gradient structure tensor over the tracking window at `p`
// over the larger (1: texture in every direction, 0: an edge or nothing).
double Isotropy(const cv::Mat& grey, const cv::Point2f& p) {
  const int half = kWindow / 2 + 1;
  const cv::Rect box = cv::Rect(cvRound(p.x) - half, cvRound(p.y) - half, 2 * half + 1, 2 * half + 1) &
                       cv::Rect(0, 0, grey.cols, grey.rows);
  cv::Mat gx, gy;
  cv::Sobel(grey(box), gx, CV_32F, 1, 0);
  cv::Sobel(grey(box), gy, CV_32F, 0, 1);
  const cv::Rect inner(1, 1, box.width - 2, box.height - 2);  // the borders' gradients are not the image's
  const double xx = gx(inner).dot(gx(inner)), yy = gy(inner).dot(gy(inner)), xy = gx(inner).dot(gy(inner));
  const double mean = (xx + yy) / 2, spread = std::sqrt((xx - yy) * (xx - yy) / 4 + xy * xy);
  return mean + spread > 0 ? (mean - spread) / (mean + spread) : 0.0;
}

// One road feature: its ray (camera frame) in frame i and the pixel it was tracked to in frame j.
struct Track {
  Eigen::Vector3d ray_i;
  Eigen::Vector2d to;
  int pair = 0;
};

// Where a camera turned to R predicts the track in frame j, minus where it was tracked (pixels);
// false when its ray misses the road or the prediction has no pixel.
bool Residual(const Track& k, const CameraModel& model, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
              const std::vector<Pose>& j_from_i, Eigen::Vector2d* r) {
  Eigen::Vector3d ground;
  Eigen::Vector2d predicted;
  if (!RayMeetsRoad(t, R * k.ray_i, &ground) || !model.Project(R.transpose() * (j_from_i[k.pair].Apply(ground) - t), &predicted)) {
    return false;
  }
  *r = predicted - k.to;
  return true;
}

}  // namespace

void ExtrinsicCorrectionOptions::Check() const {
  const OptionCheck Require("extrinsic correction");
  Require(min_distance_m > 0, "min_distance_m", min_distance_m, "> 0");
  Require(max_distance_m > min_distance_m, "max_distance_m", max_distance_m, "> min_distance_m");
  Require(vehicle_margin_m >= 0, "vehicle_margin_m", vehicle_margin_m, ">= 0");
  Require(min_travel_m > 0, "min_travel_m", min_travel_m, "> 0");
  Require(max_features >= 10, "max_features", max_features, ">= 10");
  Require(max_track_error_px > 0, "max_track_error_px", max_track_error_px, "> 0");
  Require(track_sigma_px > 0, "track_sigma_px", track_sigma_px, "> 0");
  Require(min_isotropy > 0 && min_isotropy <= 1, "min_isotropy", min_isotropy, "0 < r <= 1");
  Require(min_tracks >= 10, "min_tracks", min_tracks, ">= 10");
  Require(max_sigma_deg > 0, "max_sigma_deg", max_sigma_deg, "> 0");
  Require(min_correction_deg >= 0, "min_correction_deg", min_correction_deg, ">= 0");
  Require(max_correction_deg > min_correction_deg, "max_correction_deg", max_correction_deg, "> min_correction_deg");
}

namespace {

// One pass: the road tracked through the warp `camera` gives and the rotation fitted (not judged:
// `applied` and `reason` are left to the caller, except for too few tracks).
// `region`: where features are taken (RoadRegion), `valid`: the camera's valid pixels.
ExtrinsicCorrection EstimateOnce(const std::vector<cv::Mat>& grey, const std::vector<PlanarPose>& poses,
                                 const RigCamera& camera, const cv::Mat& region, const cv::Mat& valid,
                                 const ExtrinsicCorrectionOptions& o) {
  ExtrinsicCorrection c;
  c.camera = camera.name;
  const Eigen::Matrix3d& R0 = camera.vehicle_from_camera.R;
  const Eigen::Vector3d& t = camera.vehicle_from_camera.t;
  std::vector<Pose> j_from_i;
  std::vector<Track> tracks;
  const double spacing = std::max(3.0, camera.model.width() / 100.0);
  // The pixels worked on: the region's bounding box and a window around it.
  const cv::Rect roi = (cv::boundingRect(region) + cv::Size(2 * kWindow, 2 * kWindow) - cv::Point(kWindow, kWindow)) &
                       cv::Rect(0, 0, region.cols, region.rows);
  if (roi.empty()) {
    c.reason = "no road in view";
    return c;
  }
  for (size_t i = 0; i < grey.size(); ++i) {
    // The first later frame the camera moved min_travel_m from (the vehicle's pose; the camera
    // moves as far up to the turn, a few per cent at these intervals).
    size_t j = i + 1;
    auto travel = [&](size_t k) { return std::hypot(poses[k].x_m - poses[i].x_m, poses[k].z_m - poses[i].z_m); };
    while (j < grey.size() && travel(j) < o.min_travel_m) ++j;
    if (j >= grey.size()) break;
    // Frame i warped onto frame j through the road plane as the rig has it: road texture then
    // keeps its scale and shape (the tracker's window model holds) and sits within the rig's error
    // of where frame j shows it.
    const Pose j_from_i_pose = (poses[i].ToPose3().Inverse() * poses[j].ToPose3()).Inverse();
    const Pose i_from_j = j_from_i_pose.Inverse();
    const cv::Mat map = RoadWarp(camera, i_from_j, roi);
    cv::Mat warped;
    cv::remap(grey[i], warped, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    std::vector<cv::Point2f> corners, to, back;  // in the roi
    cv::goodFeaturesToTrack(warped, corners, o.max_features, 1e-3, spacing, region(roi));
    // A window's texture must fix both directions: on a marking's edge the tracker slides along it.
    corners.erase(std::remove_if(corners.begin(), corners.end(),
                                 [&](const cv::Point2f& p) { return Isotropy(warped, p) < o.min_isotropy; }),
                  corners.end());
    if (corners.empty()) continue;
    std::vector<std::uint8_t> status, status_back;
    std::vector<float> error;
    const cv::TermCriteria stop(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01);
    const cv::Mat later = grey[j](roi);
    cv::calcOpticalFlowPyrLK(warped, later, corners, to, status, error, cv::Size(kWindow, kWindow), 1, stop);
    back = corners;
    cv::calcOpticalFlowPyrLK(later, warped, to, back, status_back, error, cv::Size(kWindow, kWindow), 1, stop,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
    const cv::Point2f origin(static_cast<float>(roi.x), static_cast<float>(roi.y));
    for (size_t n = 0; n < corners.size(); ++n) {
      corners[n] += origin;
      to[n] += origin;
      back[n] += origin;
    }
    const int pair = static_cast<int>(j_from_i.size());
    j_from_i.push_back(j_from_i_pose);
    bool used = false;
    for (size_t n = 0; n < corners.size(); ++n) {
      if (!status[n] || !status_back[n] || cv::norm(back[n] - corners[n]) > o.max_track_error_px) continue;
      const int u = cvRound(to[n].x), v = cvRound(to[n].y);
      if (u < 0 || v < 0 || u >= valid.cols || v >= valid.rows || !valid.at<std::uint8_t>(v, u)) continue;
      // Where the corner came from in frame i (its ray; the warp's exact value).
      Track k;
      Eigen::Vector2d at;
      if (!RoadPixel(camera, i_from_j, {corners[n].x, corners[n].y}, &at) ||
          !camera.model.Unproject(at, &k.ray_i)) {
        continue;
      }
      k.to = Eigen::Vector2d(to[n].x, to[n].y);
      k.pair = pair;
      tracks.push_back(k);
      used = true;
    }
    if (used) ++c.pairs;
  }

  // Iteratively reweighted Gauss-Newton with Cauchy weights at the tracker's accuracy: a track
  // that did not move with the road (on a line along the motion, at the own car's edge, on an
  // object) is many pixels off and weighs next to nothing; the estimate starts at the rig.
  // The weights' scale starts wide (the rig's own error moves near road points by pixels) and
  // narrows to the tracker's accuracy as the estimate closes in.
  const double scale = 3 * o.track_sigma_px;
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  Eigen::Matrix3d JtWJ = Eigen::Matrix3d::Zero();
  double weighted_squares = 0.0, weights = 0.0;
  // The camera turned by a rotation vector (the rig's R at zero).
  const auto turned = [&](const Eigen::Vector3d& at) -> Eigen::Matrix3d { return RotationFromVector(at) * R0; };
  const auto residual = [&](const Track& k, const Eigen::Matrix3d& R, Eigen::Vector2d* r) {
    return Residual(k, camera.model, R, t, j_from_i, r);
  };
  // Each track's Jacobian at the rig (central differences): over the fraction of a degree the
  // estimate moves, it does not change enough to matter.
  std::vector<Eigen::Matrix<double, 2, 3>> jacobians(tracks.size());
  std::vector<bool> usable(tracks.size(), false);
  constexpr double h = 1e-5;
  std::array<Eigen::Matrix3d, 3> ahead, behind;  // the rig turned by +-h about each axis
  for (int a = 0; a < 3; ++a) {
    ahead[a] = turned(Eigen::Vector3d::Unit(a) * h);
    behind[a] = turned(-Eigen::Vector3d::Unit(a) * h);
  }
  for (size_t n = 0; n < tracks.size(); ++n) {
    bool ok = true;
    for (int a = 0; a < 3 && ok; ++a) {
      Eigen::Vector2d plus, minus;
      ok = residual(tracks[n], ahead[a], &plus) && residual(tracks[n], behind[a], &minus);
      if (ok) jacobians[n].col(a) = (plus - minus) / (2 * h);
    }
    usable[n] = ok;
  }
  for (int iteration = 0; iteration < 30; ++iteration) {
    const double now = std::max(scale, kStartScalePx * std::pow(0.5, iteration));
    JtWJ.setZero();
    Eigen::Vector3d JtWr = Eigen::Vector3d::Zero();
    weighted_squares = weights = 0.0;
    const Eigen::Matrix3d R = turned(w);
    for (size_t n = 0; n < tracks.size(); ++n) {
      Eigen::Vector2d r;
      if (!usable[n] || !residual(tracks[n], R, &r)) continue;
      const Eigen::Matrix<double, 2, 3>& J = jacobians[n];
      const double weight = 1.0 / (1.0 + r.squaredNorm() / (now * now));
      JtWJ += weight * J.transpose() * J;
      JtWr += weight * J.transpose() * r;
      weighted_squares += weight * r.squaredNorm();
      weights += weight;
    }
    if (weights <= 0) break;
    const Eigen::Vector3d delta = -JtWJ.ldlt().solve(JtWr);
    if (!delta.allFinite()) break;
    w += delta;
    if (now <= scale && delta.norm() < 1e-4 * kRadPerDeg) break;
  }
  // Inliers: within three scales of the estimate (and of the rig, for the residual before).
  double before = 0.0, after = 0.0;
  const Eigen::Matrix3d R = turned(w);
  for (const Track& k : tracks) {
    Eigen::Vector2d r0, r1;
    if (!residual(k, R0, &r0) || !residual(k, R, &r1) || r1.norm() > 3 * scale) continue;
    before += r0.squaredNorm();
    after += r1.squaredNorm();
    ++c.tracks;
  }
  if (c.tracks < o.min_tracks) {
    c.reason = Str(c.tracks, " road tracks (", tracks.size(), " tracked, ", c.pairs, " frame pairs; fewer than ",
                   o.min_tracks, ")");
    return c;
  }
  c.rms_before_px = std::sqrt(before / c.tracks);
  c.rms_px = std::sqrt(after / c.tracks);
  c.rotation_deg = w * kDegPerRad;
  // The weighted residuals' variance per weight, spread by the normal equations.
  const Eigen::Matrix3d covariance = weighted_squares / std::max(1.0, 2 * weights - 3) * JtWJ.inverse();
  for (int a = 0; a < 3; ++a) c.sigma_deg[a] = std::sqrt(std::max(0.0, covariance(a, a))) * kDegPerRad;
  return c;
}

}  // namespace

ExtrinsicCorrection EstimateExtrinsicCorrection(const std::vector<cv::Mat>& frames, const std::vector<PlanarPose>& poses,
                                                const RigCamera& camera, const Vehicle& vehicle,
                                                const ExtrinsicCorrectionOptions& o) {
  o.Check();
  if (frames.size() != poses.size()) {
    throw Error(Str("extrinsic correction: ", frames.size(), " frames but ", poses.size(), " poses"));
  }
  std::vector<cv::Mat> grey;
  for (const cv::Mat& f : frames) grey.push_back(GreyImage(f));
  // The region from the rig as given: a correction of a fraction of a degree moves its edges by a
  // pixel or two, well inside the tracking window's margin.
  const cv::Mat valid = CameraValidMask(camera);
  const cv::Mat region = RoadRegion(camera, valid, vehicle, o);
  ExtrinsicCorrection c = EstimateOnce(grey, poses, camera, region, valid, o);
  if (!c.reason.empty()) return c;
  // The tracking warps through the rig as it is, and its error distorts the warped texture a
  // little: a second pass from the first's correction tracks through nearly the right road
  // plane, so that what is left does not depend on how far off the rig started.
  if (c.rotation_deg.allFinite() && c.rotation_deg.norm() <= o.max_correction_deg) {
    const ExtrinsicCorrection second = EstimateOnce(grey, poses, CorrectedCamera(camera, c), region, valid, o);
    if (second.reason.empty()) {
      const Eigen::AngleAxisd total(RotationFromVector(second.rotation_deg * kRadPerDeg) *
                                    RotationFromVector(c.rotation_deg * kRadPerDeg));
      const double before = c.rms_before_px;
      c = second;
      c.rotation_deg = total.axis() * total.angle() * kDegPerRad;
      c.rms_before_px = before;
    }
  }
  if (!c.rotation_deg.allFinite() || !c.sigma_deg.allFinite()) {
    c.reason = "the fit did not converge";
  } else if (c.sigma_deg.maxCoeff() > o.max_sigma_deg) {
    c.reason = Str("standard error ", c.sigma_deg.maxCoeff(), " deg (more than ", o.max_sigma_deg, ")");
  } else if (c.rotation_deg.norm() > o.max_correction_deg) {
    c.reason = Str("correction ", c.rotation_deg.norm(), " deg (more than ", o.max_correction_deg, ")");
  } else if (c.rotation_deg.norm() < o.min_correction_deg) {
    c.reason = Str("correction ", c.rotation_deg.norm(), " deg, within the method's resolution (", o.min_correction_deg,
                   "): the rig is right");
    c.verified = true;
  } else {
    c.applied = c.verified = true;
  }
  return c;
}

RigCamera CorrectedCamera(const RigCamera& camera, const ExtrinsicCorrection& correction) {
  RigCamera corrected = camera;
  corrected.vehicle_from_camera.R =
      RotationFromVector(correction.rotation_deg * kRadPerDeg) * camera.vehicle_from_camera.R;
  return corrected;
}

}  // namespace dps
