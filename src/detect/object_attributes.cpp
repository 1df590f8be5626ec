#include "dps/detect/object_attributes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {

const char* ObjectClassName(ObjectClass c) {
  switch (c) {
    case ObjectClass::kVehicle: return "vehicle";
    case ObjectClass::kTruck: return "truck";
    case ObjectClass::kPedestrian: return "pedestrian";
    case ObjectClass::kPole: return "pole";
    case ObjectClass::kUnknown: break;
  }
  return "unknown";
}

std::optional<ObjectClass> ObjectClassFromName(const std::string& name) {
  for (const ObjectClass c : {ObjectClass::kUnknown, ObjectClass::kVehicle, ObjectClass::kTruck,
                              ObjectClass::kPedestrian, ObjectClass::kPole}) {
    if (name == ObjectClassName(c)) return c;
  }
  return std::nullopt;
}

void ClassOptions::Check() const {
  const OptionCheck Require("object class");
  Require(min_height_m >= 0, "min_height_m", min_height_m, ">= 0 m");
  Require(pole_max_width_m > 0, "pole_max_width_m", pole_max_width_m, "> 0 m");
  Require(person_max_length_m >= pole_max_width_m, "person_max_length_m", person_max_length_m, ">= pole_max_width_m");
  Require(vehicle_max_length_m >= person_max_length_m, "vehicle_max_length_m", vehicle_max_length_m,
          ">= person_max_length_m");
  Require(person_max_height_m > min_height_m, "person_max_height_m", person_max_height_m, "> min_height_m");
  Require(pole_min_height_m >= person_max_height_m, "pole_min_height_m", pole_min_height_m, ">= person_max_height_m");
  Require(vehicle_max_height_m > min_height_m, "vehicle_max_height_m", vehicle_max_height_m, "> min_height_m");
  Require(truck_max_height_m >= vehicle_max_height_m, "truck_max_height_m", truck_max_height_m,
          ">= vehicle_max_height_m");
}

ObjectClass ClassifyObject(double length_m, double height_m, const ClassOptions& o) {
  const bool measured = std::isfinite(height_m);
  if (measured && (height_m < o.min_height_m || height_m > o.truck_max_height_m)) return ObjectClass::kUnknown;
  if (length_m <= o.pole_max_width_m) return ObjectClass::kPole;
  if (length_m <= o.person_max_length_m) {
    if (measured && height_m > o.pole_min_height_m) return ObjectClass::kPole;
    if (measured && height_m > o.person_max_height_m) return ObjectClass::kUnknown;
    return ObjectClass::kPedestrian;
  }
  // Longer than any car: a truck or bus, unless no higher than a car (a wall, a fence, a hedge: no
  // road user's shape).
  if (length_m > o.vehicle_max_length_m) {
    return measured && height_m <= o.vehicle_max_height_m ? ObjectClass::kUnknown : ObjectClass::kTruck;
  }
  return measured && height_m > o.vehicle_max_height_m ? ObjectClass::kTruck : ObjectClass::kVehicle;
}

std::pair<double, double> FootprintExtents(const std::vector<Eigen::Vector2d>& points) {
  if (points.size() < 2) return {0.0, 0.0};
  std::vector<cv::Point2f> p;
  p.reserve(points.size());
  for (const Eigen::Vector2d& q : points) p.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
  const cv::RotatedRect r = cv::minAreaRect(p);
  return {std::max(r.size.width, r.size.height), std::min(r.size.width, r.size.height)};
}

std::optional<int> LaneOfPoint(const std::vector<LaneBoundaryRow>& boundaries, const Eigen::Vector2d& point) {
  const LaneBoundaryRow *left = nullptr, *right = nullptr;
  for (const LaneBoundaryRow& b : boundaries) {
    if (b.boundary == "left") left = &b;
    if (b.boundary == "right") right = &b;
  }
  if (!left || !right) return std::nullopt;
  const double z = point.y();
  const auto at = [z](const LaneBoundaryRow& b) {
    return b.offset_m + std::tan(b.heading_deg * kRadPerDeg) * z + 0.5 * b.curvature * z * z;
  };
  const double l = at(*left), r = at(*right), width = r - l, x = point.x();
  if (!(width > 0)) return std::nullopt;
  if (x < l) return -1 - static_cast<int>(std::floor((l - x) / width));
  if (x > r) return 1 + static_cast<int>(std::floor((x - r) / width));
  return 0;
}

void SetAttributes(const std::vector<LaneBoundaryRow>& lanes, const ClassOptions& options, Detection* d) {
  d->lane = LaneOfPoint(lanes, {(d->x_min_m + d->x_max_m) / 2, (d->z_min_m + d->z_max_m) / 2});
  const double length = d->points.size() >= 2 ? FootprintExtents(d->points).first
                                              : std::max(d->x_max_m - d->x_min_m, d->z_max_m - d->z_min_m);
  d->object_class = ObjectClassName(ClassifyObject(length, d->height_m, options));
}

std::string AttributeCells(double height_m, const std::optional<int>& lane, const std::string& object_class) {
  char height[32] = "";
  if (std::isfinite(height_m)) std::snprintf(height, sizeof(height), "%.3f", height_m);
  return Str(height, ",", lane ? std::to_string(*lane) : std::string(), ",", object_class);
}

AttributeColumns::AttributeColumns(const CsvTable& table) {
  if (table.HasColumn("height")) height = table.Column("height");
  if (table.HasColumn("lane")) lane = table.Column("lane");
  if (table.HasColumn("class")) object_class = table.Column("class");
}

void ReadAttributes(const CsvTable& table, size_t row, const AttributeColumns& columns, double* height_m,
                    std::optional<int>* lane, std::string* object_class) {
  if (columns.height >= 0 && !table.Text(row, columns.height).empty()) {
    *height_m = table.Number(row, columns.height);
    if (!std::isfinite(*height_m)) {
      throw Error(Str(table.path(), ":", table.Line(row), ": column 'height': not a finite number"));
    }
  }
  if (columns.lane >= 0 && !table.Text(row, columns.lane).empty()) *lane = table.Integer(row, columns.lane);
  if (columns.object_class >= 0) {
    const std::string& name = table.Text(row, columns.object_class);
    if (!name.empty() && !ObjectClassFromName(name)) {
      throw Error(Str(table.path(), ":", table.Line(row), ": column 'class': '", name,
                      "' is not one of unknown, vehicle, truck, pedestrian, pole"));
    }
    *object_class = name;
  }
}

}  // namespace dps
