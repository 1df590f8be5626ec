// Tests of dps-synth's renderer and outputs: truth footprints land on the pixels the renderer
// gives the object (for every camera model), truth velocities agree with truth positions across
// frames (with the ego motion integrated from can.csv), calibration marks lie on their painted
// lines, range images hold the true distances, output is deterministic, and bad scene files fail
// with a message naming the field.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "check.h"
#include "fixtures.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/scene_renderer.h"
#include "dps/synth/synth.h"
#include "dps/util/csv.h"
#include "dps/util/error.h"

namespace {

namespace fs = std::filesystem;

constexpr double kMinFootprintHitRate = 0.95;  // visible box points that land on the object
constexpr double kVelocityTolMps = 0.05;       // finite differences vs truth velocities
constexpr double kRangeTolM = 1e-3;            // range images: mm quantisation
constexpr double kMinFaceCosine = 0.2;         // faces seen more obliquely are not checked
constexpr double kMaxFootprintRangeM = 20.0;   // farther, a 320x240 object is a few pixels wide

const fs::path kTmp = fs::temp_directory_path() / "dps_test_synth";
const std::string kScenes = dps_test::kSource + "/data/scenes/";

dps::Scene Load(const std::string& name, int width = 320, int height = 240) {
  return dps_test::SmallScene(name, width, height);
}

// The scene's rig with every camera replaced by an equivalent of another model.
dps::Scene WithModel(dps::Scene s, dps::CameraModelType type) {
  for (dps::RigCamera& c : s.rig.cameras) {
    if (type == dps::CameraModelType::kUnified) {
      c.model = dps::HyperbolicToUnified(c.model);
    } else if (type == dps::CameraModelType::kFisheye) {
      // An equidistant lens whose rim shows 105 degrees from the axis, like the mirror.
      const double f = c.model.rim_radius_px() / (105.0 * M_PI / 180.0);
      Eigen::Matrix3d K = c.model.K();
      K(0, 0) = K(1, 1) = f;
      c.model = dps::CameraModel::Fisheye(c.model.width(), c.model.height(), K, {0, 0, 0, 0},
                                          c.model.rim_radius_px());
    }
  }
  return s;
}

// Points on the visible faces of each truth box project onto pixels whose id is that object
// (or an object / the own car in front of it).
void TestFootprints(const dps::Scene& scene, const char* label) {
  const dps::SceneRenderer renderer(scene);
  int hits = 0, misses = 0;
  for (int f = 0; f < scene.FrameCount(); f += 10) {
    const dps::FrameState st = renderer.StateAt(scene.FrameTime(f));
    const std::vector<dps::TruthRow> truth = dps::TruthAt(st, f);
    for (size_t c = 0; c < scene.rig.cameras.size(); ++c) {
      const dps::RigCamera& cam = scene.rig.cameras[c];
      const dps::RenderedView view = renderer.Render(st, c, f);
      const dps::Pose camera_from_vehicle = cam.vehicle_from_camera.Inverse();
      for (const dps::TruthRow& t : truth) {
        if (std::hypot(t.x_m, t.z_m) > kMaxFootprintRangeM) continue;
        const double h = t.heading_deg * M_PI / 180.0;
        const Eigen::Vector3d along(std::sin(h), 0, std::cos(h)), across(std::cos(h), 0, -std::sin(h));
        const Eigen::Vector3d centre(t.x_m, 0, t.z_m);
        // Faces: +-across (sides), +-along (ends); points at 25/50/75 % of width and height.
        for (int face = 0; face < 4; ++face) {
          const Eigen::Vector3d normal = face < 2 ? (face == 0 ? 1 : -1) * across : (face == 2 ? 1 : -1) * along;
          const Eigen::Vector3d tangent = face < 2 ? along : across;
          const double half_depth = face < 2 ? t.width_m / 2 : t.length_m / 2;
          const double extent = face < 2 ? t.length_m : t.width_m;
          for (double fa : {0.25, 0.5, 0.75}) {
            for (double fh : {0.25, 0.5, 0.75}) {
              const Eigen::Vector3d p = centre + half_depth * normal + (fa - 0.5) * extent * tangent +
                                        Eigen::Vector3d(0, -fh * t.height_m, 0);
              // Back-facing, or seen so obliquely that the face is a sliver under a pixel wide.
              const Eigen::Vector3d to_camera = (cam.vehicle_from_camera.t - p).normalized();
              if (normal.dot(to_camera) < kMinFaceCosine) continue;
              Eigen::Vector2d px;
              if (!cam.model.Project(camera_from_vehicle.Apply(p), &px) || !cam.model.InImage(px)) continue;
              const auto id = view.ids.at<std::uint16_t>(static_cast<int>(std::lround(px.y())),
                                                         static_cast<int>(std::lround(px.x())));
              if (id == dps::kIdObjectBase + t.id) {
                ++hits;
              } else if (id < dps::kIdOwnCar) {
                ++misses;  // sky, ground or paint where the object should be
              }
            }
          }
        }
      }
    }
  }
  const double rate = hits / std::max(1.0, double(hits + misses));
  std::printf("footprints %-28s %4d visible points, hit rate %.3f\n", label, hits + misses, rate);
  CHECK(hits > 50);
  CHECK(rate >= kMinFootprintHitRate);
}

std::map<std::string, std::vector<double>> Columns(const std::string& path,
                                                    const std::vector<std::string>& names) {
  const dps::CsvTable t = dps::CsvTable::Read(path);
  std::map<std::string, std::vector<double>> out;
  for (const std::string& n : names) {
    const int c = t.Column(n);
    for (size_t r = 0; r < t.rows(); ++r) out[n].push_back(t.Number(r, c));
  }
  return out;
}

// Integrates the ego pose from can.csv (trapezoid on the heading, 100 Hz samples) and checks that
// object positions, carried into the world, change as the truth velocities say.
void TestTruthVelocities(const std::string& name) {
  dps::Scene scene = Load(name, 160, 120);
  const fs::path dir = kTmp / name;
  dps::SynthOptions options;
  options.overwrite = true;
  dps::Synthesize(scene, dir.string(), options);
  auto can = Columns((dir / "can.csv").string(), {"t", "speed", "yaw_rate"});
  auto truth = Columns((dir / "truth.csv").string(), {"frame", "t", "id", "x", "z", "vx", "vz"});
  // Each camera's truth mask is written, the model's size.
  for (const dps::RigCamera& c : scene.rig.cameras) {
    const cv::Mat m = cv::imread((dir / "truth_masks" / (c.name + ".png")).string(), cv::IMREAD_UNCHANGED);
    CHECK_EQ(m.cols, c.model.width());
    CHECK_EQ(m.rows, c.model.height());
    CHECK(cv::countNonZero(m) > 0);
  }
  // Ego pose at each CAN sample.
  std::vector<double> ex{0}, ez{0}, eh{0};
  for (size_t i = 1; i < can["t"].size(); ++i) {
    const double dt = can["t"][i] - can["t"][i - 1];
    const double dh = -0.5 * (can["yaw_rate"][i] + can["yaw_rate"][i - 1]) * dt;
    const double v = 0.5 * (can["speed"][i] + can["speed"][i - 1]);
    const double hm = eh.back() + 0.5 * dh;
    ex.push_back(ex.back() + v * dt * std::sin(hm));
    ez.push_back(ez.back() + v * dt * std::cos(hm));
    eh.push_back(eh.back() + dh);
  }
  auto ego_at = [&](double t, double* x, double* z, double* h) {
    size_t i = 0;
    while (i + 1 < can["t"].size() && can["t"][i + 1] <= t + 1e-9) ++i;
    const double w = i + 1 < can["t"].size() ? (t - can["t"][i]) / (can["t"][i + 1] - can["t"][i]) : 0;
    *x = ex[i] + w * (ex[i + 1] - ex[i]);
    *z = ez[i] + w * (ez[i + 1] - ez[i]);
    *h = eh[i] + w * (eh[i + 1] - eh[i]);
  };
  // World position and velocity of object rows.
  struct W { double t, x, z, vx, vz; };
  std::map<int, std::vector<W>> by_id;
  for (size_t r = 0; r < truth["t"].size(); ++r) {
    double x, z, h;
    ego_at(truth["t"][r], &x, &z, &h);
    const double c = std::cos(h), s = std::sin(h);
    // body -> world: (x, z) -> (c x + s z, -s x + c z)
    const double bx = truth["x"][r], bz = truth["z"][r], vx = truth["vx"][r], vz = truth["vz"][r];
    by_id[static_cast<int>(truth["id"][r])].push_back(
        {truth["t"][r], x + c * bx + s * bz, z - s * bx + c * bz, c * vx + s * vz, -s * vx + c * vz});
  }
  double worst = 0;
  int pairs = 0;
  for (auto& [id, rows] : by_id) {
    for (size_t i = 1; i < rows.size(); ++i) {
      const double dt = rows[i].t - rows[i - 1].t;
      const double fx = (rows[i].x - rows[i - 1].x) / dt, fz = (rows[i].z - rows[i - 1].z) / dt;
      const double mx = 0.5 * (rows[i].vx + rows[i - 1].vx), mz = 0.5 * (rows[i].vz + rows[i - 1].vz);
      worst = std::max(worst, std::hypot(fx - mx, fz - mz));
      ++pairs;
    }
  }
  std::printf("truth velocities %-12s %d frame pairs, worst |finite difference - truth| %.4f m/s\n",
              name.c_str(), pairs, worst);
  CHECK(pairs > 30);
  CHECK(worst < kVelocityTolMps);
}

void TestCalibrationMarks() {
  dps::Scene nominal = Load("calibration", 640, 480);
  dps::Scene scene = nominal;
  scene.rig = dps::PerturbedRig(nominal);
  for (size_t c = 0; c < scene.rig.cameras.size(); ++c) {
    const double angle = dps::RotationAngleDeg(nominal.rig.cameras[c].vehicle_from_camera.R,
                                               scene.rig.cameras[c].vehicle_from_camera.R);
    CHECK(angle >= 1.0 - 1e-9 && angle <= 3.0 + 1e-9);
  }
  const dps::SceneRenderer renderer(scene);
  const dps::FrameState st = renderer.StateAt(0.0);
  const std::vector<dps::Mark> marks = dps::SampleMarks(renderer, st, 0.0);
  std::map<char, int> per_axis;
  int on_line = 0;
  for (const dps::Mark& m : marks) {
    const dps::RigCamera& cam = scene.rig.Camera(m.camera);
    Eigen::Vector3d ray;
    CHECK(cam.model.Unproject({m.u, m.v}, &ray));
    const dps::RayHit hit = renderer.Cast(st, cam.vehicle_from_camera.t, cam.vehicle_from_camera.R * ray);
    const bool ok = m.axis == 'Y' ? hit.id >= dps::kIdObjectBase : hit.id == dps::kIdPaint;
    on_line += ok;
    ++per_axis[m.axis];
  }
  std::printf("calibration marks: %zu (X %d, Y %d, Z %d), %d on their line or pole\n", marks.size(),
              per_axis['X'], per_axis['Y'], per_axis['Z'], on_line);
  CHECK_EQ(on_line, static_cast<int>(marks.size()));
  CHECK(per_axis['X'] >= 20 && per_axis['Y'] >= 6 && per_axis['Z'] >= 20);
  // The noisy marks differ from the exact ones by about the configured 0.5 px.
  const std::vector<dps::Mark> noisy = dps::SampleMarks(renderer, st, 0.5);
  CHECK_EQ(noisy.size(), marks.size());
  double ss = 0;
  for (size_t i = 0; i < marks.size() && i < noisy.size(); ++i) {
    ss += std::pow(noisy[i].u - marks[i].u, 2) + std::pow(noisy[i].v - marks[i].v, 2);
  }
  const double sigma = std::sqrt(ss / (2.0 * marks.size()));
  CHECK_NEAR(sigma, 0.5, 0.05);
}

void TestRangeImagesAndDeterminism() {
  dps::Scene scene = Load("lead_car");
  dps::SynthOptions options;
  options.frames = 2;
  options.write_truth_images = true;
  options.overwrite = true;
  dps::Synthesize(scene, (kTmp / "a").string(), options);
  dps::Synthesize(scene, (kTmp / "b").string(), options);
  // The same bytes twice.
  int files = 0, same = 0;
  for (const auto& e : fs::recursive_directory_iterator(kTmp / "a")) {
    if (!e.is_regular_file()) continue;
    const fs::path other = kTmp / "b" / fs::relative(e.path(), kTmp / "a");
    std::ifstream fa(e.path(), std::ios::binary), fb(other, std::ios::binary);
    const std::string ca((std::istreambuf_iterator<char>(fa)), {}), cb((std::istreambuf_iterator<char>(fb)), {});
    ++files;
    same += !ca.empty() && ca == cb;
  }
  CHECK(files >= 13);  // rig, can, frames, truth, 2 cameras x 2 frames x (image, range, ids)
  CHECK_EQ(same, files);
  // Another seed, another image.
  scene.seed = 99;
  dps::Synthesize(scene, (kTmp / "c").string(), options);
  const cv::Mat a = cv::imread((kTmp / "a/left/000000.png").string());
  const cv::Mat c = cv::imread((kTmp / "c/left/000000.png").string());
  CHECK(!a.empty() && !c.empty() && cv::norm(a, c, cv::NORM_L1) > 0);
  // Range images: a ground pixel's range times its ray's downward component is the camera height.
  const cv::Mat range = cv::imread((kTmp / "a/range/left/000001.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat ids = cv::imread((kTmp / "a/ids/left/000001.png").string(), cv::IMREAD_UNCHANGED);
  CHECK(range.type() == CV_16U && ids.type() == CV_16U);
  const dps::RigCamera& cam = scene.rig.Camera("left");
  double worst = 0;
  int ground = 0;
  for (int v = 0; v < range.rows; v += 3) {
    for (int u = 0; u < range.cols; u += 3) {
      if (ids.at<std::uint16_t>(v, u) != dps::kIdGround || range.at<std::uint16_t>(v, u) >= 65535) continue;
      Eigen::Vector3d ray;
      CHECK(cam.model.Unproject({double(u), double(v)}, &ray));
      const double down = (cam.vehicle_from_camera.R * ray).y();
      const double height = range.at<std::uint16_t>(v, u) / 1000.0 * down;
      worst = std::max(worst, std::abs(height + cam.vehicle_from_camera.t.y()));
      ++ground;
    }
  }
  CHECK(ground > 500);
  CHECK(worst < kRangeTolM);
  // Nothing is left under a temporary name.
  for (const auto& e : fs::recursive_directory_iterator(kTmp)) {
    CHECK(e.path().filename().string().find(".tmp") == std::string::npos);
  }
  // An existing folder is not replaced without overwrite.
  options.overwrite = false;
  CHECK_THROWS_WITH(dps::Synthesize(scene, (kTmp / "a").string(), options), dps::Error, "already exists");
}

void TestBadScenes() {
  const std::string rig = kScenes + "../rigs/omni_pair.yaml";
  const std::string head = "%YAML:1.0\n---\nrig: " + rig + "\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"%YAML:1.0\n---\nfps: 15\n", "field 'rig': missing"},
      {"%YAML:1.0\n---\nrig: nowhere.yaml\n", "nowhere.yaml: file not found"},
      {head + "objects:\n   - { id: 1, kind: car, x: 0, z: 10, length: -4 }\n", "objects[0]: field 'length'"},
      {head + "objects:\n   - { id: 1, kind: bus, x: 0, z: 10 }\n", "unknown kind 'bus'"},
      {head + "objects:\n   - { id: 1, x: 0 }\n", "objects[0]: field 'z': missing"},
      {head + "objects:\n   - { id: 1, x: 0, z: 5 }\n   - { id: 1, x: 3, z: 5 }\n", "duplicate id 1"},
      {head + "ego:\n   - { t: 2, speed: 5 }\n   - { t: 1, speed: 5 }\n", "field 'ego'"},
      {head + "render: { supersample: 0 }\n", "render: field 'supersample'"},
      {head + "fps: -3\n", "field 'fps'"},
      {head + "kind: calibration\n", "field 'lines'"},
      {head + "road: { lane_width: 0 }\n", "road: field 'lane_width'"},
  };
  int i = 0;
  for (const auto& [text, needle] : cases) {
    const fs::path p = kTmp / ("bad" + std::to_string(i++) + ".yaml");
    std::ofstream(p) << text;
    CHECK_THROWS_WITH(dps::ReadScene(p.string()), dps::Error, needle);
  }
}

// Scene detail's geometry, against where it was placed: the kerb's face and the raised pavement
// beyond it, the road short of it; the body's sill and a mirror housing behind each camera.
void TestSceneDetail() {
  dps::Scene s = Load("empty_road");
  s.render.kerb_height_m = 0.15;
  s.render.kerb_offset_left_m = 0.4;
  s.render.kerb_offset_right_m = 0.4;
  s.render.own_sill_height_m = 0.3;
  s.render.own_sill_inset_m = 0.1;
  s.render.mirror_housing_m = 0.2;
  s.render.mirror_housing_drop_m = 0.05;
  const dps::SceneRenderer renderer(s);
  const dps::FrameState st = renderer.StateAt(0.0);
  const double kerb_x = s.road.ego_lane_center_x_m + (s.road.lanes_right + 0.5) * s.road.lane_width_m + 0.4;
  const Eigen::Vector3d eye(0.0, -1.2, 3.0);  // in front of the own car
  const auto cast = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& towards) {
    return renderer.Cast(st, from, (towards - from).normalized());
  };
  const dps::RayHit pavement = cast(eye, {kerb_x + 1.0, -0.15, 9.0});
  CHECK_EQ(pavement.id, std::uint16_t{dps::kIdKerb});
  CHECK_NEAR(pavement.point_vehicle.y(), -0.15, 1e-9);
  CHECK_NEAR(pavement.point_vehicle.x(), kerb_x + 1.0, 1e-9);
  const dps::RayHit face = cast(eye, {kerb_x, -0.07, 9.0});
  CHECK_EQ(face.id, std::uint16_t{dps::kIdKerb});
  CHECK_NEAR(face.point_vehicle.x(), kerb_x, 1e-9);
  const dps::RayHit road = cast(eye, {kerb_x - 0.3, 0.0, 9.0});
  CHECK_EQ(road.id, std::uint16_t{dps::kIdGround});
  CHECK_NEAR(road.point_vehicle.y(), 0.0, 1e-9);
  // Left of the road too, and below the pavement's level behind the kerb nothing is ground.
  const double left_kerb = s.road.ego_lane_center_x_m - (s.road.lanes_left + 0.5) * s.road.lane_width_m - 0.4;
  CHECK_EQ(cast(eye, {left_kerb - 2.0, 0.0, 8.0}).id, std::uint16_t{dps::kIdKerb});
  // The body's side under the doors is set in by the sill inset; above the sill it is the body.
  const double hw = s.rig.vehicle.width_m / 2;
  const dps::RayHit low = renderer.Cast(st, {hw + 1.0, -0.15, 0.0}, {-1.0, 0.0, 0.0});
  CHECK_EQ(low.id, std::uint16_t{dps::kIdOwnCar});
  CHECK_NEAR(low.point_vehicle.x(), hw - 0.1, 1e-9);
  const dps::RayHit door = renderer.Cast(st, {hw + 1.0, -0.5, 0.0}, {-1.0, 0.0, 0.0});
  CHECK_NEAR(door.point_vehicle.x(), hw, 1e-9);
  // Straight back from each camera: its housing, 4 cm behind it.
  for (const dps::RigCamera& c : s.rig.cameras) {
    const dps::RayHit back = renderer.Cast(st, c.vehicle_from_camera.t, {0.0, 0.0, -1.0});
    CHECK_EQ(back.id, std::uint16_t{dps::kIdOwnCar});
    CHECK_NEAR(back.distance_m, 0.04, 1e-9);
  }
  // The truth masks: the pixel looking straight back sees the housing, not the world; one looking
  // out and down at the road beside the camera sees the world; without the housing, straight
  // back is the world again.
  dps::Scene plain = Load("empty_road");
  const dps::SceneRenderer plain_renderer(plain);
  for (size_t i = 0; i < s.rig.cameras.size(); ++i) {
    const dps::RigCamera& c = s.rig.cameras[i];
    const double out = c.vehicle_from_camera.t.x() < 0 ? -1.0 : 1.0;
    Eigen::Vector2d back, beside;
    CHECK(c.model.Project(c.vehicle_from_camera.R.transpose() * Eigen::Vector3d(0.0, 0.02, -1.0), &back));
    CHECK(c.model.Project(c.vehicle_from_camera.R.transpose() * Eigen::Vector3d(out, 1.0, 0.0), &beside));
    const auto at = [](const cv::Mat& m, const Eigen::Vector2d& p) {
      return m.at<std::uint8_t>(static_cast<int>(std::lround(p.y())), static_cast<int>(std::lround(p.x())));
    };
    const cv::Mat mask = renderer.WorldMask(i), plain_mask = plain_renderer.WorldMask(i);
    CHECK_EQ(mask.type(), CV_8U);
    CHECK_EQ(at(mask, back), 0);
    CHECK_EQ(at(mask, beside), 255);
    CHECK_EQ(at(plain_mask, back), 255);
  }
  // Without the detail (the shipped look) the same rays meet the road and the open air.
  const dps::FrameState plain_st = plain_renderer.StateAt(0.0);
  CHECK_EQ(plain_renderer.Cast(plain_st, eye, (Eigen::Vector3d(kerb_x + 1.0, 0.0, 9.0) - eye).normalized()).id,
           std::uint16_t{dps::kIdGround});
  CHECK(plain_renderer.Cast(plain_st, s.rig.cameras[0].vehicle_from_camera.t, {0.0, 0.0, -1.0}).id != dps::kIdOwnCar);
  // Patches and cracks change the road's look, not its geometry.
  dps::Scene worn = plain;
  worn.render.ground_patches = 1.0;
  worn.render.cracks = 1.0;
  const dps::SceneRenderer worn_renderer(worn);
  const dps::RenderedView a = plain_renderer.Render(plain_st, 0, 0), b = worn_renderer.Render(worn_renderer.StateAt(0.0), 0, 0);
  CHECK(cv::norm(a.ids, b.ids, cv::NORM_INF) == 0.0);
  cv::Mat diff;
  cv::absdiff(a.image, b.image, diff);
  std::vector<cv::Mat> channels;
  cv::split(diff, channels);
  const cv::Mat ground = a.ids == dps::kIdGround;
  const cv::Mat changed_pixels = ((channels[0] | channels[1] | channels[2]) > 0) & ground;
  const double changed = cv::countNonZero(changed_pixels);
  std::printf("patches and cracks: %.0f of %d road pixels changed\n", changed, cv::countNonZero(ground));
  CHECK(changed > 0.3 * cv::countNonZero(ground));
}

}  // namespace

int main() {
  fs::remove_all(kTmp);
  fs::create_directories(kTmp);
  for (const char* name : {"lead_car", "overtaking", "parked_cars"}) {
    const dps::Scene s = Load(name);
    TestFootprints(s, (std::string(name) + " hyperbolic").c_str());
    if (std::string(name) == "lead_car") {
      TestFootprints(WithModel(s, dps::CameraModelType::kUnified), "lead_car unified");
      TestFootprints(WithModel(s, dps::CameraModelType::kFisheye), "lead_car fisheye");
    }
  }
  TestTruthVelocities("left_turn");
  TestTruthVelocities("overtaking");
  TestCalibrationMarks();
  TestRangeImagesAndDeterminism();
  TestBadScenes();
  TestSceneDetail();
  fs::remove_all(kTmp);
  return dps_test::Report();
}
