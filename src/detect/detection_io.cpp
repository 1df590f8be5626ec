#include "dps/detect/detection_io.h"

#include <cmath>

#include "dps/detect/object_attributes.h"
#include "dps/util/atomic_file.h"
#include "dps/util/csv.h"
#include "dps/util/error.h"

namespace dps {

void WriteDetections(const std::vector<Detection>& detections, const std::string& path) {
  AtomicOutputFile out(path);
  out.stream().precision(6);
  out.stream() << std::fixed;
  out.stream() << "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points,height,lane,class\n";
  for (const Detection& d : detections) {
    out.stream() << d.frame << "," << d.t_s << "," << d.source << "," << d.id << "," << d.x_m << ","
                 << d.z_m << "," << d.range_m << "," << d.x_min_m << "," << d.x_max_m << "," << d.z_min_m
                 << "," << d.z_max_m << "," << d.n_points << "," << AttributeCells(d.height_m, d.lane, d.object_class)
                 << "\n";
  }
  out.Commit();
}

std::vector<Detection> ReadDetections(const std::string& path) {
  const CsvTable t = CsvTable::Read(path);
  const int frame = t.Column("frame"), time = t.Column("t"), source = t.Column("source"), id = t.Column("id");
  const int x = t.Column("x"), z = t.Column("z"), range = t.Column("range");
  const int x_min = t.Column("x_min"), x_max = t.Column("x_max"), z_min = t.Column("z_min"), z_max = t.Column("z_max");
  const int n = t.Column("n_points");
  const AttributeColumns attributes(t);  // extra columns, not in DESIGN.md §3.4
  std::vector<Detection> out;
  for (size_t r = 0; r < t.rows(); ++r) {
    Detection d;
    d.frame = t.Integer(r, frame);
    d.t_s = t.Number(r, time);
    d.source = t.Text(r, source);
    d.id = t.Integer(r, id);
    d.x_m = t.Number(r, x);
    d.z_m = t.Number(r, z);
    d.range_m = t.Number(r, range);
    d.x_min_m = t.Number(r, x_min);
    d.x_max_m = t.Number(r, x_max);
    d.z_min_m = t.Number(r, z_min);
    d.z_max_m = t.Number(r, z_max);
    d.n_points = t.Integer(r, n);
    ReadAttributes(t, r, attributes, &d.height_m, &d.lane, &d.object_class);
    const std::pair<const char*, double> numbers[] = {{"t", d.t_s}, {"x", d.x_m}, {"z", d.z_m}, {"range", d.range_m},
                                                      {"x_min", d.x_min_m}, {"x_max", d.x_max_m}, {"z_min", d.z_min_m},
                                                      {"z_max", d.z_max_m}};
    for (const auto& [name, value] : numbers) {
      if (!std::isfinite(value)) throw Error(Str(path, ":", t.Line(r), ": column '", name, "': not a finite number"));
    }
    out.push_back(d);
  }
  return out;
}

}  // namespace dps
