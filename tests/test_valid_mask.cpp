// Valid-pixel masks: the field's edge estimated from images (synthetic with a known edge, and a
// real fisheye), masks in rig.yaml and views, and stereo that never matches across the edge; the
// own car estimated from rendered drives against the renderer's record of it.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "check.h"
#include "dps/camera/rig_io.h"
#include "dps/camera/valid_mask.h"
#include "dps/stereo/sad_stereo.h"
#include "dps/stereo/virtual_view.h"
#include "dps/synth/randomize.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/scene_renderer.h"
#include "dps/util/error.h"
#include "fixtures.h"

namespace fs = std::filesystem;

namespace {

// A textured scene (random blobs of brightness 60..220) that differs from frame to frame.
cv::Mat Texture(cv::Size size, unsigned seed) {
  cv::theRNG().state = seed;
  cv::Mat small(size.height / 8 + 1, size.width / 8 + 1, CV_8U);
  cv::randu(small, 60, 220);
  cv::Mat image;
  cv::resize(small, image, size, 0, 0, cv::INTER_CUBIC);
  cv::Mat noise(size, CV_8U);
  cv::randu(noise, 0, 30);
  return image + noise;
}

// A camera whose model knows no rim, and frames whose field really ends at a circle of radius
// `edge` around the principal point, with a dark object inside the field (a black car) and sensor
// noise beyond it.
void TestEstimatedFieldEdge() {
  const int w = 640, h = 480;
  Eigen::Matrix3d K;
  K << 150, 0, 322.5, 0, 150, 236.0, 0, 0, 1;
  const dps::CameraModel model = dps::CameraModel::Hyperbolic(w, h, K, 1.1, 0.9);
  const double edge = 205.0;
  std::vector<cv::Mat> frames;
  for (unsigned i = 0; i < 6; ++i) {
    cv::Mat f = Texture({w, h}, 17 + i);
    cv::Mat outside(h, w, CV_8U, cv::Scalar(255));
    cv::circle(outside, cv::Point(322, 236), static_cast<int>(edge), cv::Scalar(0), cv::FILLED);
    f.setTo(0, outside);
    cv::rectangle(f, cv::Rect(300, 300, 40, 30), cv::Scalar(6), cv::FILLED);  // dark in every frame
    cv::Mat noise(h, w, CV_8U);
    cv::randu(noise, 0, 8);
    frames.push_back(f + noise);
  }
  const dps::FieldMaskOptions o;
  const cv::Mat mask = dps::EstimateFieldMask(frames, model, o);
  const double margin = std::ceil(o.edge_margin_fraction * w);
  int wrong_inside = 0, wrong_outside = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double r = std::hypot(x - 322.5, y - 236.0);
      if (r < edge - margin - 2 && !mask.at<std::uint8_t>(y, x)) ++wrong_inside;
      if (r > edge + 1 && mask.at<std::uint8_t>(y, x)) ++wrong_outside;
    }
  }
  std::printf("estimated field edge: %d pixels inside the edge marked unseen, %d beyond it marked seen\n",
              wrong_inside, wrong_outside);
  CHECK_EQ(wrong_inside, 0);  // the dark object inside the field stays valid
  CHECK_EQ(wrong_outside, 0);
  // Bad inputs.
  CHECK_THROWS_WITH(dps::EstimateFieldMask(std::vector<cv::Mat>(), model, o), dps::Error, "no frames");
  CHECK_THROWS_WITH(dps::EstimateFieldMask(std::vector<cv::Mat>(1, cv::Mat(10, 10, CV_8U)), model, o), dps::Error, "10x10");
  dps::FieldMaskOptions bad;
  bad.dark_fraction = 1.5;
  CHECK_THROWS_WITH(bad.Check(), dps::Error, "dark_fraction");
}

// A real car's fisheye (data/real/fisheye_car): the image circle found in the image is centred near
// the calibrated principal point, and the dark corners lie beyond it. (The lens model here is an
// equidistant one with the calibrated K, valid over the whole image, so that the circle comes from
// the image alone.)
void TestRealFisheye() {
  const std::string dir = dps_test::kSource + "/data/real/fisheye_car";
  const cv::Mat image = cv::imread(dir + "/images/left.png", cv::IMREAD_COLOR);
  CHECK(!image.empty());
  if (image.empty()) return;
  const dps::CameraModel calibrated = dps::ReadOpenCVFisheye(dir + "/yaml/left.yaml");
  const dps::CameraModel model =
      dps::CameraModel::Fisheye(calibrated.width(), calibrated.height(), calibrated.K(), {0, 0, 0, 0});
  const cv::Mat mask = dps::EstimateFieldMask({image}, model);
  const int cy = static_cast<int>(std::lround(model.K()(1, 2)));
  int first = -1, last = -1;
  for (int x = 0; x < mask.cols; ++x) {
    if (!mask.at<std::uint8_t>(cy, x)) continue;
    if (first < 0) first = x;
    last = x;
  }
  const double centre = (first + last) / 2.0, fraction = cv::countNonZero(mask) / double(mask.total());
  std::printf("real fisheye: circle from column %d to %d on row %d (centre %.1f, cx %.1f); %.3f of the pixels see\n",
              first, last, cy, centre, model.K()(0, 2), fraction);
  CHECK_NEAR(centre, model.K()(0, 2), 15.0);
  CHECK(last - first > 0.8 * mask.cols);
  for (const cv::Point corner : {cv::Point(2, 2), cv::Point(mask.cols - 3, 2), cv::Point(2, mask.rows - 3)}) {
    CHECK_EQ(mask.at<std::uint8_t>(corner), 0);
  }
  CHECK_EQ(mask.at<std::uint8_t>(cy, static_cast<int>(model.K()(0, 2))), 255);
}

// rig.yaml's `mask:` is read relative to the file, checked for size, written back, and the views
// built from the camera are invalid wherever it is 0.
void TestRigMask() {
  const fs::path dir = dps_test::ScratchDir("dps_test_valid_mask");
  dps::Rig rig = dps_test::OmniRig();
  dps::RigCamera& left = rig.cameras[0].name == "left" ? rig.cameras[0] : rig.cameras[1];
  cv::Mat mask(left.model.height(), left.model.width(), CV_8U, cv::Scalar(255));
  mask.colRange(0, mask.cols / 2).setTo(0);  // the left half of the image sees nothing
  fs::create_directories(dir / "masks");
  cv::imwrite((dir / "masks" / "left.png").string(), mask);
  left.mask_file = "masks/left.png";
  dps::WriteRig(rig, (dir / "rig.yaml").string());
  const dps::Rig back = dps::ReadRig((dir / "rig.yaml").string());
  CHECK_EQ(back.Camera("left").mask_file, std::string("masks/left.png"));
  CHECK_EQ(cv::countNonZero(back.Camera("left").mask != mask), 0);
  CHECK(back.Camera("right").mask.empty());
  const cv::Mat valid = dps::CameraValidMask(back.Camera("left"));
  CHECK_EQ(cv::countNonZero(valid.colRange(0, mask.cols / 2)), 0);
  // A view: where its pixels take their source from the masked half, it is invalid.
  const dps::ViewSpec spec = dps::FrontViewSpec(back, "left", "right", 200, 100, 85);
  const dps::VirtualView with(back.Camera("left"), spec), without(rig.Camera("right"), spec);
  int sourced_in_masked = 0;
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      const cv::Vec2f p = with.omni_coordinates().at<cv::Vec2f>(y, x);
      if (with.mask().at<std::uint8_t>(y, x) && p[0] < mask.cols / 2) ++sourced_in_masked;
    }
  }
  CHECK_EQ(sourced_in_masked, 0);
  CHECK(cv::countNonZero(with.mask()) < cv::countNonZero(without.mask()));
  // The own car as estimated (RigCamera::own_car) does not take pixels from the view: it marks the
  // view's pixels whose source it holds.
  const dps::VirtualView plain(rig.Camera("left"), spec);
  std::vector<float> rows;  // the source rows the view takes
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      if (plain.mask().at<std::uint8_t>(y, x)) rows.push_back(plain.omni_coordinates().at<cv::Vec2f>(y, x)[1]);
    }
  }
  std::nth_element(rows.begin(), rows.begin() + static_cast<long>(rows.size() / 2), rows.end());
  const int split = static_cast<int>(std::lround(rows[rows.size() / 2]));
  dps::RigCamera with_car = rig.Camera("left");
  with_car.own_car = cv::Mat(mask.size(), CV_8U, cv::Scalar(0));
  with_car.own_car.rowRange(split, mask.rows).setTo(255);  // below the view's median source row
  const dps::VirtualView car_view(with_car, spec);
  CHECK(plain.own_car().empty());
  CHECK_EQ(cv::countNonZero(car_view.mask() != plain.mask()), 0);
  int wrong = 0, marked = 0;
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      const cv::Vec2f p = car_view.omni_coordinates().at<cv::Vec2f>(y, x);
      const bool lower = car_view.mask().at<std::uint8_t>(y, x) && std::lround(p[1]) >= split;
      wrong += lower != (car_view.own_car().at<std::uint8_t>(y, x) != 0);
      marked += lower;
    }
  }
  CHECK_EQ(wrong, 0);
  CHECK(marked > 0);
  // A mask of the wrong size names the file.
  cv::imwrite((dir / "masks" / "left.png").string(), cv::Mat(10, 20, CV_8U, cv::Scalar(255)));
  CHECK_THROWS_WITH(dps::ReadRig((dir / "rig.yaml").string()), dps::Error, "left.png: the mask is 20x10");
  fs::remove_all(dir);
}

// Stereo across a field's edge: the two images end at different curves (as two mirrors' fields
// do in a front pair). Without masks the edges are matched; with them, every disparity is the
// scene's and no window touches an unseen pixel.
void TestMatchingStopsAtTheEdge() {
  const int w = 320, h = 160, d_true = 10;
  const cv::Mat scene = Texture({w + d_true, h}, 5);
  // left(x) = right(x - d_true)
  cv::Mat left = scene.colRange(0, w).clone(), right = scene.colRange(d_true, w + d_true).clone();
  cv::Mat left_valid(h, w, CV_8U, cv::Scalar(255)), right_valid(h, w, CV_8U, cv::Scalar(255));
  for (int x = 0; x < w; ++x) {
    const int l_edge = 40 + static_cast<int>(20 * std::sin(x / 50.0)), r_edge = 30 + x / 16;
    left_valid.col(x).rowRange(0, l_edge).setTo(0);
    right_valid.col(x).rowRange(0, r_edge).setTo(0);
  }
  left.setTo(0, left_valid == 0);
  right.setTo(0, right_valid == 0);
  dps::StereoOptions o = dps::DetectionStereoOptions();
  o.num_disparities = 32;
  const auto count_wrong = [&](const cv::Mat& disparity) {
    int wrong = 0, valid = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const float v = disparity.at<float>(y, x);
        if (!std::isfinite(v)) continue;
        ++valid;
        wrong += std::abs(v - d_true) > 1.0f;
      }
    }
    return std::make_pair(wrong, valid);
  };
  dps::SadStereoMatcher matcher(o);
  const auto [wrong_blind, valid_blind] = count_wrong(matcher.Compute(left, right));
  const cv::Mat masked = matcher.Compute(left, right, left_valid, right_valid);
  const auto [wrong_masked, valid_masked] = count_wrong(masked);
  std::printf("matching across a field's edge: %d of %d disparities wrong without masks, %d of %d with them\n",
              wrong_blind, valid_blind, wrong_masked, valid_masked);
  CHECK(wrong_blind > 0);  // the edge is matched when nobody says it is one
  CHECK_EQ(wrong_masked, 0);
  CHECK(valid_masked > 0.5 * valid_blind);
  // No disparity whose reference window or matched window touches an unseen pixel.
  int touching = 0;
  const int rw = o.block_width / 2, rh = o.block_height / 2;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float v = masked.at<float>(y, x);
      if (!std::isfinite(v)) continue;
      const int m = static_cast<int>(std::floor(x - v));
      const cv::Rect ref(x - rw, y - rh, o.block_width, o.block_height), other(m - rw, y - rh, o.block_width + 1, o.block_height);
      const cv::Rect image(0, 0, w, h);
      touching += cv::countNonZero(left_valid(ref & image) == 0) > 0 || cv::countNonZero(right_valid(other & image) == 0) > 0;
    }
  }
  CHECK_EQ(touching, 0);
  CHECK_THROWS_WITH(matcher.Compute(left, right, cv::Mat(5, 5, CV_8U), right_valid), dps::Error, "validity mask");
}

}  // namespace

// The own car estimated from rendered drives of every camera family (randomised rigs, own cars,
// roads and objects) against the renderer's own record of the pixels that see the own car. A car
// keeping pace ahead (the lead car), the sky and the raised pavement (untextured in the renderer)
// hold still too: objects and the textured road must not be taken for the car.
void TestOwnCarFromRenderedDrives() {
  int cameras = 0, estimated = 0;
  double own_pixels = 0, own_found = 0, textured = 0, textured_taken = 0, objects = 0, objects_taken = 0;
  for (const char* family : {"lead_car", "following", "parked_cars"}) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      const dps::Scene base = dps::ReadScene(dps_test::kSource + "/data/scenes/" + family + ".yaml");
      const dps::RandomizedScene drawn = dps::Randomize(base, seed);
      const dps::Scene& scene = drawn.scene;
      const dps::SceneRenderer renderer(scene);
      // Every third frame of the first two seconds.
      std::vector<int> frames;
      for (int f = 0; f < scene.FrameCount() && scene.FrameTime(f) <= 2.0; f += 3) frames.push_back(f);
      const dps::FrameState first = renderer.StateAt(scene.FrameTime(frames.front()));
      const dps::FrameState last = renderer.StateAt(scene.FrameTime(frames.back()));
      const double travel = std::hypot(last.ego.x_m - first.ego.x_m, last.ego.z_m - first.ego.z_m);
      for (size_t c = 0; c < scene.rig.cameras.size(); ++c) {
        std::vector<cv::Mat> images;
        cv::Mat ids;
        for (const int f : frames) {
          const dps::RenderedView v = renderer.Render(renderer.StateAt(scene.FrameTime(f)), c, f);
          images.push_back(v.image);
          ids = v.ids;
        }
        // As processed: the rig with its calibration error, the field's edge estimated first.
        dps::RigCamera camera = drawn.processing_rig.cameras[c];
        camera.mask = dps::EstimateFieldMask(images, camera.model);
        const cv::Mat own = dps::EstimateOwnCarMask(images, camera, drawn.processing_rig.vehicle, travel);
        ++cameras;
        if (own.empty()) continue;
        ++estimated;
        const cv::Mat truth = ids == dps::kIdOwnCar, object = ids >= dps::kIdObjectBase;
        const cv::Mat road = (ids == dps::kIdGround) | (ids == dps::kIdPaint);
        const int t = cv::countNonZero(truth), found = cv::countNonZero(truth & own);
        const int r = cv::countNonZero(road), r_taken = cv::countNonZero(road & own);
        const int o = cv::countNonZero(object), o_taken = cv::countNonZero(object & own);
        std::printf("%s %llu %s (%s): own car %d px, found %.3f; road %d of %d px taken, objects %d of %d\n", family,
                    static_cast<unsigned long long>(seed), camera.name.c_str(), drawn.camera_family.c_str(), t,
                    t ? found / double(t) : 1.0, r_taken, r, o_taken, o);
        own_pixels += t;
        own_found += found;
        textured += r;
        textured_taken += r_taken;
        objects += o;
        objects_taken += o_taken;
      }
    }
  }
  std::printf("own car: estimated for %d of %d cameras; %.3f of its pixels found; %.4f of the road's and %.4f of "
              "the objects' pixels taken\n", estimated, cameras, own_found / own_pixels, textured_taken / textured,
              objects_taken / objects);
  // The part below the camera's level where the road is resolved (valid_mask.h): 0.40 of the own
  // car; nothing else.
  CHECK_EQ(estimated, cameras);
  CHECK(own_found >= 0.35 * own_pixels);
  CHECK(textured_taken <= 0.002 * textured);
  CHECK(objects_taken <= 0.001 * objects);
}

// No estimate when nothing tells the car from the road: the car stood still, or its frames are
// all alike.
void TestOwnCarNeedsMotion() {
  const dps::RandomizedScene drawn = dps::Randomize(dps::ReadScene(dps_test::kSource + "/data/scenes/lead_car.yaml"), 1);
  const dps::SceneRenderer renderer(drawn.scene);
  std::vector<cv::Mat> moving, same;
  for (int f = 0; f < 30; f += 3) {
    moving.push_back(renderer.Render(renderer.StateAt(drawn.scene.FrameTime(f)), 0, f).image);
    same.push_back(moving.front());
  }
  const dps::RigCamera& camera = drawn.processing_rig.cameras[0];
  CHECK(dps::EstimateOwnCarMask(moving, camera, drawn.processing_rig.vehicle, 1.0).empty());  // below 3 m
  CHECK(dps::EstimateOwnCarMask(same, camera, drawn.processing_rig.vehicle, 20.0).empty());
  CHECK(dps::EstimateOwnCarMask({moving.front()}, camera, drawn.processing_rig.vehicle, 20.0).empty());
  CHECK(!dps::EstimateOwnCarMask(moving, camera, drawn.processing_rig.vehicle, 20.0).empty());
  dps::OwnCarMaskOptions bad;
  bad.min_road_to_car = 1.0;
  CHECK_THROWS_WITH(dps::EstimateOwnCarMask(moving, camera, drawn.processing_rig.vehicle, 20.0, bad), dps::Error,
                    "min_road_to_car");
}

// `--rendered-drives`: the own car on the twelve rendered drives only (the slow part, CTest's
// test_valid_mask_rendered, labelled slow); without it everything else.
int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "--rendered-drives") {
    TestOwnCarFromRenderedDrives();
    return dps_test::Report();
  }
  TestOwnCarNeedsMotion();
  TestEstimatedFieldEdge();
  TestRealFisheye();
  TestRigMask();
  TestMatchingStopsAtTheEdge();
  return dps_test::Report();
}
