// dps — a ray caster for synthetic scenes: every pixel of every camera model is traced through
// CameraModel::Unproject and the camera's pose in the vehicle frame at that frame's ego pose,
// against the ground plane (asphalt texture, lane or parking markings), box-shaped objects, the
// own car and the sky. Besides the image it keeps, per pixel, what the centre ray hit (an id
// buffer) and how far (a range buffer), which is the ground truth that tests score against.
//
// Textures are fixed to the world and to the objects (a function of position, not of the frame),
// so that consecutive frames show the same surface detail, as real ones do; only the image noise
// changes from frame to frame.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/synth/scene.h"

namespace dps {

// Values of the id buffer (CV_16U).
enum SurfaceId : std::uint16_t {
  kIdNoRay = 0,          // outside the rim / field of view: the pixel sees nothing (black)
  kIdSky = 1,
  kIdGround = 2,         // asphalt
  kIdPaint = 3,          // lane markings, painted parking lines
  kIdOwnCar = 4,         // the vehicle that carries the rig
  kIdKerb = 5,           // a kerb's face and the raised pavement beyond it
  kIdObjectBase = 1000,  // object with truth id k has id kIdObjectBase + k
};

// One camera's rendering of one frame.
struct RenderedView {
  cv::Mat image;    // CV_8UC3 (BGR)
  cv::Mat ids;      // CV_16U, SurfaceId of the pixel's centre ray
  cv::Mat range_m;  // CV_32F, distance from the viewpoint along the centre ray; 0 = no surface
};

// An object's box in the vehicle frame at one instant.
struct BoxInstance {
  int id = 0;                     // truth id
  const SceneObject* object = nullptr;
  Eigen::Vector2d centre_xz{0, 0};  // footprint centre, vehicle frame
  double heading_rad = 0.0;       // relative to the vehicle's +Z, positive towards +X
  PlanarPose world;               // the same in the world frame (texture coordinates)
  // The radius of the sphere about the box's centre through its corners, a little larger than
  // exact (so that rounding never makes a ray test miss the box): rays that miss it miss the box
  // (StateAt fills it).
  double bound_radius_m = 0.0;
};

// Where the world is at one instant, seen from the vehicle.
struct FrameState {
  double t_s = 0.0;
  PlanarPose ego;                  // vehicle pose in the world
  Pose world_from_vehicle;         // the same as a 3-D transform
  std::vector<BoxInstance> boxes;  // the scene's objects in the vehicle frame
};

// The first surface along a ray.
struct RayHit {
  double distance_m = 0.0;  // along the ray; 0 when nothing (sky) was hit
  std::uint16_t id = kIdSky;
  Eigen::Vector3d point_vehicle{0, 0, 0};
  Eigen::Vector3d point_world{0, 0, 0};  // ground hits: the point in the world (texture coords)
  int box = -1;             // index into FrameState::boxes for objects
  int face = 0;             // objects: 0 side (along the length), 1 end, 2 top
  double face_a_m = 0.0;    // objects: coordinate along the face, metres
  double face_h_m = 0.0;    // objects: height above the ground, metres
};

class SceneRenderer {
 public:
  // Precomputes every camera's sub-pixel rays (vehicle frame). The scene must outlive the
  // renderer.
  explicit SceneRenderer(const Scene& scene);

  // The ego pose and the object boxes at time t_s.
  FrameState StateAt(double t_s) const;

  // Renders camera `camera_index` of the scene's rig; `frame_index` seeds the image noise.
  RenderedView Render(const FrameState& state, size_t camera_index, int frame_index) const;

  // The first surface hit by a ray from `origin_vehicle` along the unit direction `dir_vehicle`.
  RayHit Cast(const FrameState& state, const Eigen::Vector3d& origin_vehicle,
              const Eigen::Vector3d& dir_vehicle) const;

  // Which pixels of camera `camera_index` see the world (CV_8U, 255): those whose centre ray the
  // camera model has and that do not meet the own car (body, cabin, sill, mirror housings).
  // dps-synth writes it as the drive's truth_masks/<camera>.png, for dps-eval's visibility.
  cv::Mat WorldMask(size_t camera_index) const;

  const Scene& scene() const { return scene_; }

 private:
  // Scene detail: a ground point in the shadow of an object or the own car; the verge beyond the
  // road's outer edges; clouds and the sun's halo on a sky colour.
  bool InShadow(const FrameState& st, const Eigen::Vector3d& ground_point, const Eigen::Vector3d& light) const;
  bool OnVerge(double world_x) const;
  // The first entry of a ray into the own car's boxes (+inf: none).
  double OwnCarEntry(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const;
  // Cast with the own car's entry along the ray given (OwnCarEntry(o, d)): the own car is fixed
  // in the vehicle frame, so a camera's rays enter it at the same distance in every frame.
  RayHit CastWithOwnCar(const FrameState& st, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_car) const;
  // The first entry into a kerb and its pavement (+inf: none); `face` = entry axis (1: top).
  double KerbEntry(const FrameState& st, const Eigen::Vector3d& o, const Eigen::Vector3d& d, int* face) const;
  // Asphalt (with patches and cracks), a verge or pavement at a world point on the road's surface.
  cv::Vec3f GroundColour(const Eigen::Vector3d& world, bool pavement, std::uint32_t seed) const;
  cv::Vec3f SkyDetail(const RenderOptions& render, const Eigen::Vector3d& d, const Eigen::Vector3d& light,
                      float elevation, std::uint32_t seed, cv::Vec3f sky) const;
  struct CameraRays {
    int width = 0, height = 0;
    std::vector<Eigen::Vector3f> dirs;  // (samples + 1) per pixel; centre ray first; NaN = none
    std::vector<double> own_car_t;      // each ray's OwnCarEntry from the camera
  };
  cv::Vec3f Shade(const FrameState& state, const Eigen::Vector3d& dir, const RayHit& hit,
                  const Eigen::Vector3d& light_vehicle) const;

  const Scene& scene_;
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> own_boxes_;  // [lo, hi], vehicle frame
  std::vector<CameraRays> rays_;
  int samples_ = 4;
};

}  // namespace dps
