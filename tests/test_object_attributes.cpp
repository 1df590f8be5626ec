// Object attributes: classes of road users' measured sizes (each from its physical size, as a
// camera would see it from behind, from the side, partly), footprint extents of rotated boxes,
// lanes of points among straight, turned and curved boundaries worked out by hand, the extra
// columns of detections.csv and tracks.csv written and read back (and bad ones refused, old files
// without them read), and dps-eval's class and lane scores on detections with known attributes.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "check.h"
#include "dps/detect/detection_io.h"
#include "dps/detect/object_attributes.h"
#include "dps/eval/evaluation.h"
#include "dps/map/tracks_io.h"
#include "dps/util/error.h"

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

std::string ClassOf(double a, double b, double height) {
  return dps::ObjectClassName(dps::ClassifyObject(std::max(a, b), height));
}

void TestClasses() {
  // A car 4.5 x 1.8 m, 1.5 m high: whole, from behind (its back only), from the side, height unknown.
  CHECK_EQ(ClassOf(4.5, 1.8, 1.5), std::string("vehicle"));
  CHECK_EQ(ClassOf(1.8, 0.1, 1.5), std::string("vehicle"));
  CHECK_EQ(ClassOf(4.5, 0.2, 1.4), std::string("vehicle"));
  CHECK_EQ(ClassOf(4.5, 1.8, kNaN), std::string("vehicle"));
  // A truck 10 x 2.5 m, 3.5 m high; its back only (2.5 m wide, 3.5 m high); a bus's side.
  CHECK_EQ(ClassOf(10.0, 2.5, 3.5), std::string("truck"));
  CHECK_EQ(ClassOf(2.5, 0.2, 3.5), std::string("truck"));
  CHECK_EQ(ClassOf(12.0, 0.3, kNaN), std::string("truck"));
  // A pedestrian 0.6 x 0.5 m, 1.75 m; a cyclist from behind (0.7 m, 1.8 m).
  CHECK_EQ(ClassOf(0.6, 0.5, 1.75), std::string("pedestrian"));
  CHECK_EQ(ClassOf(0.7, 0.1, 1.8), std::string("pedestrian"));
  // A pole 0.2 m thick, 3 m high; measured wider than it is (0.6 m) but taller than anyone.
  CHECK_EQ(ClassOf(0.2, 0.2, 3.0), std::string("pole"));
  CHECK_EQ(ClassOf(0.6, 0.3, 3.0), std::string("pole"));
  // A kerb (0.15 m high) and a bridge deck 6 m up: neither.
  CHECK_EQ(ClassOf(5.0, 0.2, 0.15), std::string("unknown"));
  CHECK_EQ(ClassOf(8.0, 3.0, 6.0), std::string("unknown"));
  // A wall beside the road, 8 m long and 1.2 m high: longer than any car, no higher than one; a
  // van 6 m long, 2.5 m high, is still a vehicle.
  CHECK_EQ(ClassOf(8.0, 0.3, 1.2), std::string("unknown"));
  CHECK_EQ(ClassOf(6.0, 2.0, 2.5), std::string("vehicle"));
  // Names both ways.
  for (const char* name : {"unknown", "vehicle", "truck", "pedestrian", "pole"}) {
    CHECK(dps::ObjectClassFromName(name).has_value());
    CHECK_EQ(std::string(dps::ObjectClassName(*dps::ObjectClassFromName(name))), std::string(name));
  }
  CHECK(!dps::ObjectClassFromName("car").has_value());
  dps::ClassOptions bad;
  bad.vehicle_max_length_m = 1.0;  // shorter than a person
  CHECK_THROWS_WITH(bad.Check(), dps::Error, "vehicle_max_length_m");
  // The evaluation's expectations by truth kind.
  CHECK_EQ(dps::ExpectedClass("car"), std::string("vehicle"));
  CHECK_EQ(dps::ExpectedClass("bus"), std::string("truck"));
  CHECK_EQ(dps::ExpectedClass("pedestrian"), std::string("pedestrian"));
  CHECK_EQ(dps::ExpectedClass("wall"), std::string("unknown"));
  CHECK_EQ(dps::ExpectedClass("motorbike"), std::string("pedestrian"));
}

void TestExtents() {
  // The corners and edge points of a 4.5 x 1.8 m box turned by 30 degrees about (3, 7).
  const double c = std::cos(kPi / 6), s = std::sin(kPi / 6);
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i <= 10; ++i) {
    for (const double w : {-0.9, 0.9}) {
      const double l = -2.25 + 0.45 * i;
      points.emplace_back(3.0 + c * w + s * l, 7.0 - s * w + c * l);
    }
  }
  const auto [length, width] = dps::FootprintExtents(points);
  CHECK_NEAR(length, 4.5, 1e-3);
  CHECK_NEAR(width, 1.8, 1e-3);
  CHECK_EQ(dps::FootprintExtents({{1.0, 2.0}}).first, 0.0);
}

dps::LaneBoundaryRow Boundary(const char* name, double offset, double heading_deg = 0.0, double curvature = 0.0) {
  dps::LaneBoundaryRow b;
  b.boundary = name;
  b.offset_m = offset;
  b.heading_deg = heading_deg;
  b.curvature = curvature;
  b.type = "dashed";
  return b;
}

void TestLanes() {
  // A 3.5 m lane from -1.75 to 1.75 m.
  const std::vector<dps::LaneBoundaryRow> straight = {Boundary("left2", -5.25), Boundary("left", -1.75),
                                                      Boundary("right", 1.75)};
  CHECK(dps::LaneOfPoint(straight, {0.0, 12.0}) == 0);
  CHECK(dps::LaneOfPoint(straight, {-1.7, -8.0}) == 0);
  CHECK(dps::LaneOfPoint(straight, {-1.8, 5.0}) == -1);
  CHECK(dps::LaneOfPoint(straight, {-5.0, 5.0}) == -1);
  CHECK(dps::LaneOfPoint(straight, {-5.5, 5.0}) == -2);
  CHECK(dps::LaneOfPoint(straight, {3.0, 5.0}) == 1);
  CHECK(dps::LaneOfPoint(straight, {6.0, 5.0}) == 2);
  // Turned 10 degrees to the right: at z = 20 m the lane lies 20 tan(10 deg) = 3.53 m to the
  // right, so x = 3.5 is in it and x = 0 in the lane on its left.
  const std::vector<dps::LaneBoundaryRow> turned = {Boundary("left", -1.75, 10.0), Boundary("right", 1.75, 10.0)};
  CHECK(dps::LaneOfPoint(turned, {3.5, 20.0}) == 0);
  CHECK(dps::LaneOfPoint(turned, {0.0, 20.0}) == -1);
  // Curving left at 1/100 m: at z = 20 m the lane has moved 0.5 * 0.01 * 400 = 2 m to the left.
  const std::vector<dps::LaneBoundaryRow> curved = {Boundary("left", -1.75, 0.0, -0.01), Boundary("right", 1.75, 0.0, -0.01)};
  CHECK(dps::LaneOfPoint(curved, {-3.5, 20.0}) == 0);
  CHECK(dps::LaneOfPoint(curved, {0.5, 20.0}) == 1);
  // Without the ego lane's right boundary: unknown.
  CHECK(!dps::LaneOfPoint({Boundary("left", -1.75), Boundary("right2", 5.25)}, {0.0, 5.0}).has_value());
}

void TestFiles() {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "dps_test_object_attributes";
  std::filesystem::create_directories(dir);
  dps::Detection a = dps::DetectionFromPoints({{1.0, 8.0}, {2.8, 8.1}}, "front");
  a.frame = 3;
  a.t_s = 0.2;
  a.height_m = 1.52;
  a.lane = -1;
  a.object_class = "vehicle";
  dps::Detection b = dps::DetectionFromPoints({{-4.0, 1.0}}, "left");
  b.frame = 3;
  b.t_s = 0.2;
  const std::string path = (dir / "detections.csv").string();
  dps::WriteDetections({a, b}, path);
  const std::vector<dps::Detection> back = dps::ReadDetections(path);
  CHECK_EQ(back.size(), size_t{2});
  CHECK_NEAR(back[0].height_m, 1.52, 1e-9);
  CHECK(back[0].lane == -1);
  CHECK_EQ(back[0].object_class, std::string("vehicle"));
  CHECK(std::isnan(back[1].height_m));
  CHECK(!back[1].lane.has_value());
  CHECK(back[1].object_class.empty());
  // A file of another writer without the extra columns; one with a class that is not one.
  {
    std::ofstream f(dir / "old.csv");
    f << "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points\n0,0,front,0,1,8,8.06,1,1,8,8,1\n";
  }
  const std::vector<dps::Detection> old = dps::ReadDetections((dir / "old.csv").string());
  CHECK(old.size() == 1 && std::isnan(old[0].height_m) && !old[0].lane && old[0].object_class.empty());
  {
    std::ofstream f(dir / "bad.csv");
    f << "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points,height,lane,class\n"
      << "0,0,front,0,1,8,8.06,1,1,8,8,1,1.5,0,lorry\n";
  }
  CHECK_THROWS_WITH(dps::ReadDetections((dir / "bad.csv").string()), dps::Error, "bad.csv:2: column 'class': 'lorry'");
  {
    std::ofstream f(dir / "bad_lane.csv");
    f << "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points,height,lane,class\n"
      << "0,0,front,0,1,8,8.06,1,1,8,8,1,1.5,0.5,vehicle\n";
  }
  CHECK_THROWS_WITH(dps::ReadDetections((dir / "bad_lane.csv").string()), dps::Error, "lane");
  // Tracks.
  dps::TrackState t;
  t.frame = 4;
  t.t_s = 0.25;
  t.id = 7;
  t.confirmed = true;
  t.height_m = 3.4;
  t.lane = 2;
  t.object_class = "truck";
  const std::string tracks = (dir / "tracks.csv").string();
  dps::WriteTracks({t}, tracks);
  const std::vector<dps::TrackState> tb = dps::ReadTracks(tracks);
  CHECK(tb.size() == 1 && tb[0].lane == 2 && tb[0].object_class == "truck");
  CHECK_NEAR(tb[0].height_m, 3.4, 1e-9);
  std::filesystem::remove_all(dir);
}

// dps-eval's attribute scores: two objects with truth lanes, detections with known lanes and
// classes.
void TestScores() {
  const dps::TruthRow car{0, 0.0, 1, "car", 0.0, 10.0, 0.0, 4.5, 1.8, 1.5, 0, 0};      // ego lane
  const dps::TruthRow truck{0, 0.0, 2, "truck", 3.5, 8.0, 0.0, 9.0, 2.5, 3.5, 0, 0};   // lane +1
  const dps::TruthRow pole{0, 0.0, 3, "pole", -7.5, 6.0, 0.0, 0.2, 0.2, 3.0, 0, 0};    // lane -2
  auto det = [](double x, double z, int lane, const char* cls) {
    dps::Detection d = dps::DetectionFromPoints({{x, z}}, "front");
    d.lane = lane;
    d.object_class = cls;
    return d;
  };
  dps::EvaluationOptions o;
  o.truth_lanes[0] = {Boundary("left", -1.75), Boundary("right", 1.75)};
  // The car right on both; the truck's lane wrong (0), its class right; the pole's lane right, its
  // class wrong.
  const dps::EvaluationResult r =
      dps::Evaluate({det(0.0, 7.75, 0, "vehicle"), det(3.0, 3.5, 0, "truck"), det(-7.5, 5.9, -2, "pedestrian")},
                    {car, truck, pole}, o);
  CHECK_EQ(r.overall.matched_detections, 3);
  CHECK_EQ(r.classes.judged, 3);
  CHECK_EQ(r.classes.correct, 2);
  // The confusion by the class expected: the pole taken for a pedestrian.
  CHECK_EQ(r.class_confusion.at("pole").at("pedestrian"), 1);
  CHECK_EQ(r.class_confusion.at("vehicle").at("vehicle"), 1);
  CHECK(r.class_confusion.at("pole").count("pole") == 0);
  CHECK(dps::EvaluationJson(r).find("\"class_confusion\": {\"pole\": {\"pedestrian\": 1}, \"truck\": {\"truck\": 1}, "
                                    "\"vehicle\": {\"vehicle\": 1}}") != std::string::npos);
  CHECK(dps::EvaluationTable(r).find("  pole: pedestrian 1\n") != std::string::npos);
  CHECK_EQ(r.lanes.judged, 3);
  CHECK_EQ(r.lanes.correct, 2);
  CHECK(dps::EvaluationJson(r).find("\"lanes\": {\"judged\": 3, \"correct\": 2") != std::string::npos);
  // Without truth lanes no lane is judged.
  const dps::EvaluationResult n = dps::Evaluate({det(0.0, 7.75, 0, "vehicle")}, {car}, dps::EvaluationOptions());
  CHECK_EQ(n.lanes.judged, 0);
  CHECK(std::isnan(n.lanes.Accuracy()));
}

}  // namespace

int main() {
  TestClasses();
  TestExtents();
  TestLanes();
  TestFiles();
  TestScores();
  return dps_test::Report();
}
