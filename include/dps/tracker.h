// dps — tracking obstacles over frames with a Kalman filter per object (seeds/004, section 4.3;
// the first paper's wish for objects with position and velocity).
//
// State per track: position and ground velocity (px, pz, vx, vz) in a world frame that the ego
// motion (CAN speed and yaw rate) carries the vehicle through, so that parked things stay put and
// the velocity is over the ground. Constant-velocity motion with white acceleration noise. A
// track follows one point of its object: its position measurement is the detection's ground
// points near the track's prediction (averaged within local_radius_m), mapped into the world
// through the ego pose (the measurement model is linear given the pose, so the extended filter
// reduces to the plain one), with a standard deviation growing with range and with the
// detection's extent; side detections add their motion-stereo velocity along the camera's
// displacement as a scalar velocity measurement. Detections are assigned to tracks by the
// Hungarian method on the Mahalanobis distance, within a chi-square gate. A track is born from an
// unassigned detection, confirmed after `confirm_hits` hits and deleted after `max_misses`
// frames without one.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "dps/detection.h"
#include "dps/ego_motion.h"

namespace dps {

struct TrackerOptions {
  double accel_sigma_mps2 = 8.0;      // process noise, > 0
  double meas_sigma_m = 0.3;          // measurement sigma at range 0, > 0
  double meas_sigma_per_m = 0.04;     // ... growing by this per metre of range, >= 0
  // ... and by this fraction of the detection's extent along x and z (its nearest point slides
  // along the object as the visible part changes), >= 0.
  double extent_sigma_fraction = 0.3;
  // A track follows one point of its object: each frame the detection's points within this of
  // the point nearest to the prediction, averaged, are the measurement, >= 0.
  double local_radius_m = 0.5;
  double init_speed_sigma_mps = 8.0;  // velocity uncertainty of a new track, > 0
  double gate_chi2 = 9.21;            // Mahalanobis gate (2 dof, 99 %), > 0
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
  struct Track {
    int id;
    Eigen::Vector4d x;
    Eigen::Matrix4d P;
    int hits = 0, misses = 0, age = 0;
    bool confirmed = false;
  };
  static void ApplyMotion(const Detection& d, const Eigen::Matrix2d& world_from_vehicle, Track* t);
  TrackerOptions options_;
  std::vector<Track> tracks_;
  int next_id_ = 1;
  double last_t_ = 0.0;
  bool started_ = false;
};

// The minimum-cost assignment of rows to columns (Hungarian method). cost: rows x cols; entries
// >= `forbidden` may not be used. Returns for each row its column or -1.
std::vector<int> HungarianAssignment(const std::vector<std::vector<double>>& cost, double forbidden);

// tracks.csv (DESIGN.md §3.5) for the confirmed tracks, written atomically.
void WriteTracks(const std::vector<TrackState>& tracks, const std::string& path);
std::vector<TrackState> ReadTracks(const std::string& path);

}  // namespace dps
