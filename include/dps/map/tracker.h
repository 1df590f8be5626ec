// dps — tracking obstacles over frames with a Kalman filter per object (the fisheye obstacle-
// detection summary, AJAST 2017, after Häne et al., IROS 2015, section 4.3; Gandhi & Trivedi's
// wish for objects with position and velocity).
//
// State per track: position, ground velocity and turn rate (px, pz, vx, vz, w) in a world frame
// that the ego motion (CAN speed and yaw rate) carries the vehicle through, so that parked things
// stay put and the velocity is over the ground. An extended Kalman filter with a constant-turn
// model (the velocity turns by w dt per step) and white acceleration noise, larger along the
// track's axis (its velocity, or the road when it stands) than across it. A track follows one
// point of its object: its position measurement is the detection's ground points near the
// track's prediction (averaged within local_radius_m), mapped into the world through the ego pose,
// with a standard deviation growing with range and with the detection's extent; when those points
// are an end where the view cut the object (Detection::clipped_ends), the followed point may be
// out of view beyond it and only the offset across the axis is measured. Side detections add
// their motion-stereo velocity along the camera's displacement as a gated scalar measurement.
// Every hit also measures the velocity from the object's shape: the detection's points are
// registered onto those of a hit about registration_span_s earlier (RegisterPoints), and the shift
// over the time between is a velocity measurement. The followed point alone cannot see an object
// slide along its own face (a car ahead seen as one row of points across the road: the point
// nearest to a drifting prediction drifts with it); the registered shape can, by its ends. When a
// view's edge cut the detection, that end moves with the view: only the velocity across the
// track's axis is measured then.
// Detections are assigned to tracks by the Hungarian method on the Mahalanobis distance, within
// a chi-square gate. A track is born from an unassigned detection, confirmed after
// `confirm_hits` hits and deleted after `max_misses` frames without one.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "dps/camera/ego_motion.h"
#include "dps/detect/detection.h"

namespace dps {

struct TrackerOptions {
  // Process noise: acceleration along the track's axis (see axis_min_speed_mps) and across it
  // (a car turning at 15 deg/s and 7 m/s accelerates 1.8 m/s^2 sideways), > 0.
  double accel_sigma_mps2 = 8.0;
  double across_accel_sigma_mps2 = 3.0;
  // Constant turn: the turn rate's random change, rad/s^2, >= 0, and a new track's turn rate
  // uncertainty (rad/s, >= 0; its turn rate starts at 0).
  double turn_accel_sigma_radps2 = 0.3;
  double init_turn_sigma_radps = 0.3;
  double meas_sigma_m = 0.3;          // measurement sigma at range 0, > 0
  double meas_sigma_per_m = 0.04;     // ... growing by this per metre of range, >= 0
  // ... and by this fraction of the detection's extent along x and z (its nearest point slides
  // along the object as the visible part changes), >= 0.
  double extent_sigma_fraction = 0.3;
  // A track follows one point of its object: each frame the detection's points within this of
  // the point nearest to the prediction, averaged, are the measurement, >= 0.
  double local_radius_m = 0.5;
  // When the detection's point nearest to the prediction lies within clip_radius_m of an end cut
  // by the view's edge (Detection::clipped_ends), the followed point may be beyond it, hidden, by
  // up to max_hidden_m along the track's axis: only the offset across the axis is measured. The
  // axis is the track's velocity from axis_min_speed_mps on, else the road's (vehicle heading).
  double clip_radius_m = 0.5;     // >= 0
  double max_hidden_m = 6.0;      // >= 0
  double axis_min_speed_mps = 2.0;  // >= 0
  // A new track's velocity uncertainty along the road (the vehicle's heading) and across it
  // (vehicles mostly drive along the road), > 0.
  double init_speed_sigma_mps = 8.0;
  double init_across_speed_sigma_mps = 1.0;
  double gate_chi2 = 9.21;            // Mahalanobis gate (2 dof, 99 %), > 0
  double motion_gate_chi2 = 6.63;     // gate of a motion-stereo velocity (1 dof, 99 %), > 0
  // Velocity by registration (see above): the earlier hit is the oldest at least span and at
  // most twice span old (0 = no registration velocity); points pair with their nearest
  // neighbour within gate_m; at least min_overlap of the earlier points must pair. The
  // measurement's standard deviation is (sigma_m + the pairs' RMS distance) / the time between,
  // combined with the velocity change over half that time at accel_sigma_mps2 (the shift is the
  // mean velocity over the interval); gated like the positions (gate_chi2).
  double registration_span_s = 0.2;   // >= 0
  double registration_sigma_m = 0.4;  // > 0
  double registration_gate_m = 0.75;  // > 0
  double registration_min_overlap = 0.6;  // 0..1
  // Standing or moving: beside the moving (constant-turn) filter each track keeps a standing one
  // (its followed point fixed in the world, drifting by standing_drift_sigma m per sqrt(s)) and the
  // probability of each from how well it predicted every measurement, the models switching at
  // model_switch_per_s (0 = moving model only). The reported velocity is the moving model's times
  // its probability: a parked car's noisy or sliding followed point no longer reads as motion,
  // while a vehicle passing at speed is told from a standing one within a few frames.
  double model_switch_per_s = 0.1;    // >= 0
  double standing_drift_sigma = 0.1;  // > 0
  int confirm_hits = 3;               // >= 1
  int max_misses = 5;                 // >= 1
  double predict_ahead_s = 1.0;       // the predicted position reported with each track, >= 0

  void Check() const;
};

// One track as reported for a frame (DESIGN.md §3.5), in the current vehicle frame.
struct TrackState {
  int frame = 0;
  double t_s = 0.0;
  int id = 0;
  double x_m = 0.0, z_m = 0.0;       // position
  double vx_mps = 0.0, vz_mps = 0.0; // ground velocity, vehicle frame axes
  double sigma_x_m = 0.0, sigma_z_m = 0.0;
  int age = 0;                       // frames since the track was born
  // The object's size on the ground as its detections showed it: the 80th percentile of their
  // extents along the track's current axis (its velocity above axis_min_speed_mps, else the
  // vehicle's heading) and across it, over its last 30 hits. A lower bound of the object's footprint where
  // the cameras saw only part of it. tracks.csv's extra columns length, width.
  double length_m = 0.0, width_m = 0.0;
  // The top's height above the road: the 80th percentile of the measured heights of its last 30
  // hits (NaN: none measured). tracks.csv's extra column height. The lane and the class are the
  // pipeline's (object_attributes.h), from the frame's lanes and this size: extra columns lane,
  // class.
  double height_m = std::numeric_limits<double>::quiet_NaN();
  std::optional<int> lane;
  std::string object_class;
  bool confirmed = false;
  Eigen::Vector2d predicted{0, 0};   // position predict_ahead_s ahead (vehicle frame now)
  Eigen::Matrix2d predicted_cov = Eigen::Matrix2d::Identity();
};

class Tracker {
 public:
  explicit Tracker(const TrackerOptions& options = TrackerOptions());

  // Advances to a frame at t_s whose vehicle pose in the tracker's world is `world_from_vehicle`,
  // and updates the tracks with that frame's detections. Returns every live track (confirmed or
  // not) in the current vehicle frame.
  std::vector<TrackState> Update(int frame, double t_s, const PlanarPose& world_from_vehicle,
                                 const std::vector<Detection>& detections);

 private:
  using State = Eigen::Matrix<double, 5, 1>;
  using Cov = Eigen::Matrix<double, 5, 5>;
  struct Track {
    int id;
    State x;  // px, pz, vx, vz (world), turn rate (rad/s, towards +x)
    Cov P;
    int hits = 0, misses = 0, age = 0;
    bool confirmed = false;
    // The standing model: the followed point's position (world) and covariance, and the log odds
    // of standing against moving.
    Eigen::Vector2d standing{0, 0};
    Eigen::Matrix2d standing_P = Eigen::Matrix2d::Identity();
    double standing_log_odds = 0.0;
    // The last hits' times and ground points (world), for the registration velocity.
    std::vector<std::pair<double, std::vector<Eigen::Vector2d>>> shapes;
    // The last hits' extents (x and z sizes in their frame's vehicle axes) with that frame's
    // world_from_vehicle rotation, for the size along and across the track's current axis.
    std::vector<std::pair<Eigen::Vector2d, Eigen::Matrix2d>> extents;
    std::vector<double> heights;  // the last hits' measured heights
  };
  // A frame's detections in the world: nearest points z, all ground points, the ends the view cut,
  // and the measurement covariances.
  struct Measurements {
    std::vector<Eigen::Vector2d> z;
    std::vector<std::vector<Eigen::Vector2d>> points, clipped_ends;
    std::vector<Eigen::Matrix2d> R;
  };
  // Detection j's followed point for one track, and whether it is an end the view cut.
  struct Measured {
    Eigen::Vector2d point;
    bool clipped = false;
  };
  // Tracks paired with detections: measured[i][j] for track i and detection j, across[i] the unit
  // vector across track i's axis, assigned[i] track i's detection (-1: none).
  struct Association {
    std::vector<std::vector<Measured>> measured;
    std::vector<Eigen::Vector2d> across;
    std::vector<int> assigned;
  };
  // The steps of Update.
  void PredictTracks(double dt, const Eigen::Matrix2d& world_from_vehicle);
  Measurements InWorld(const std::vector<Detection>& detections, const PlanarPose& ego,
                       const Eigen::Matrix2d& world_from_vehicle) const;
  Measured FollowedPoint(const Measurements& m, size_t j, const Eigen::Vector2d& prediction) const;
  Association Associate(const Measurements& m, const Eigen::Matrix2d& world_from_vehicle) const;
  std::vector<bool> UpdateTracks(double t_s, const std::vector<Detection>& detections, const Measurements& m,
                                 const Association& a, const Eigen::Matrix2d& world_from_vehicle);
  void StartTracks(double t_s, const std::vector<Detection>& detections, const Measurements& m,
                   const std::vector<bool>& used, const Eigen::Matrix2d& world_from_vehicle);
  std::vector<TrackState> Report(int frame, double t_s, const PlanarPose& ego,
                                 const Eigen::Matrix2d& world_from_vehicle) const;
  Eigen::Vector2d Axis(const Track& t, const Eigen::Matrix2d& world_from_vehicle) const;
  Eigen::Matrix2d AccelCovariance(const Track& t, const Eigen::Matrix2d& world_from_vehicle) const;
  Cov ProcessNoise(const Eigen::Matrix2d& accel, double dt) const;
  static State Predict(const State& x, double dt, Cov* F);
  static double StandingProbability(const Track& t);
  static void ApplyMotion(const Detection& d, const Eigen::Matrix2d& world_from_vehicle, double gate_chi2, Track* t);
  void ApplyRegistration(double t_s, const std::vector<Eigen::Vector2d>& points, bool cut,
                         const Eigen::Matrix2d& world_from_vehicle, Track* t) const;
  // A measurement of H x (M dimensions) updating both models; ScalarUpdate is the M = 1 case.
  template <int M>
  static void Update(const Eigen::Matrix<double, M, 5>& H, const Eigen::Matrix<double, M, 1>& innovation,
                     const Eigen::Matrix<double, M, M>& covariance, double gate_chi2, Track* t);
  static void ScalarUpdate(const Eigen::Matrix<double, 1, 5>& H, double innovation, double variance, double gate_chi2,
                           Track* t);
  TrackerOptions options_;
  std::vector<Track> tracks_;
  int next_id_ = 1;
  double last_t_ = 0.0;
  bool started_ = false;
};

// Registers point set `from` onto `to` by a translation (iterative closest points): starting at
// `initial`, each point of `from` moved by the shift pairs with its nearest point of `to` if
// within gate_m, and the shift becomes the pairs' mean offset; ten rounds or until it settles.
// True when at least 3 points and min_overlap of `from` pair at the end; then *shift and
// *rms_m (the pairs' root mean square distance) are set.
bool RegisterPoints(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to,
                    const Eigen::Vector2d& initial, double gate_m, double min_overlap, Eigen::Vector2d* shift,
                    double* rms_m);

// The minimum-cost assignment of rows to columns (Hungarian method). cost: rows x cols; entries
// >= `forbidden` may not be used. Returns for each row its column or -1.
std::vector<int> HungarianAssignment(const std::vector<std::vector<double>>& cost, double forbidden);

}  // namespace dps
