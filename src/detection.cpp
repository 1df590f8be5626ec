#include "dps/detection.h"

#include <cmath>
#include <functional>
#include <map>
#include <limits>

#include "dps/atomic_file.h"
#include "dps/csv.h"
#include "dps/error.h"

namespace dps {

Detection DetectionFromPoints(const std::vector<Eigen::Vector2d>& points, const std::string& source) {
  Detection d;
  d.source = source;
  d.points = points;
  d.n_points = static_cast<int>(points.size());
  d.x_min_m = d.z_min_m = std::numeric_limits<double>::infinity();
  d.x_max_m = d.z_max_m = -std::numeric_limits<double>::infinity();
  d.range_m = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& p : points) {
    d.x_min_m = std::min(d.x_min_m, p.x());
    d.x_max_m = std::max(d.x_max_m, p.x());
    d.z_min_m = std::min(d.z_min_m, p.y());
    d.z_max_m = std::max(d.z_max_m, p.y());
    const double r = p.norm();
    if (r < d.range_m) {
      d.range_m = r;
      d.x_m = p.x();
      d.z_m = p.y();
    }
  }
  return d;
}

std::vector<Detection> FuseDetections(const std::vector<Detection>& in, double merge_distance_m) {
  const size_t n = in.size();
  std::vector<size_t> parent(n);
  for (size_t i = 0; i < n; ++i) parent[i] = i;
  std::function<size_t(size_t)> root = [&](size_t i) { return parent[i] == i ? i : parent[i] = root(parent[i]); };
  auto points_of = [](const Detection& d) {
    return d.points.empty() ? std::vector<Eigen::Vector2d>{{d.x_m, d.z_m}} : d.points;
  };
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      if (in[i].frame != in[j].frame) continue;
      bool close = false;
      for (const Eigen::Vector2d& a : points_of(in[i])) {
        for (const Eigen::Vector2d& b : points_of(in[j])) {
          if ((a - b).norm() <= merge_distance_m) {
            close = true;
            break;
          }
        }
        if (close) break;
      }
      if (close) parent[root(i)] = root(j);
    }
  }
  std::vector<Detection> out;
  std::vector<int> slot(n, -1);
  for (size_t i = 0; i < n; ++i) {
    const size_t r = root(i);
    if (slot[r] < 0) {
      slot[r] = static_cast<int>(out.size());
      out.push_back(in[i]);
      out.back().points = points_of(in[i]);
      continue;
    }
    Detection& m = out[slot[r]];
    const std::vector<Eigen::Vector2d> extra = points_of(in[i]);
    std::vector<Eigen::Vector2d> points = m.points;
    points.insert(points.end(), extra.begin(), extra.end());
    const std::string source = in[i].range_m < m.range_m ? in[i].source : m.source;
    const int frame = m.frame;
    const double t = m.t_s;
    m = DetectionFromPoints(points, source);
    m.frame = frame;
    m.t_s = t;
  }
  std::map<std::pair<int, std::string>, int> next_id;
  for (Detection& d : out) d.id = next_id[{d.frame, d.source}]++;
  return out;
}

void WriteDetections(const std::vector<Detection>& detections, const std::string& path) {
  AtomicOutputFile out(path);
  out.stream().precision(6);
  out.stream() << std::fixed;
  out.stream() << "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points\n";
  for (const Detection& d : detections) {
    out.stream() << d.frame << "," << d.t_s << "," << d.source << "," << d.id << "," << d.x_m << ","
                 << d.z_m << "," << d.range_m << "," << d.x_min_m << "," << d.x_max_m << "," << d.z_min_m
                 << "," << d.z_max_m << "," << d.n_points << "\n";
  }
  out.Commit();
}

std::vector<Detection> ReadDetections(const std::string& path) {
  const CsvTable t = CsvTable::Read(path);
  const int frame = t.Column("frame"), time = t.Column("t"), source = t.Column("source"), id = t.Column("id");
  const int x = t.Column("x"), z = t.Column("z"), range = t.Column("range");
  const int x_min = t.Column("x_min"), x_max = t.Column("x_max"), z_min = t.Column("z_min"), z_max = t.Column("z_max");
  const int n = t.Column("n_points");
  std::vector<Detection> out;
  for (size_t r = 0; r < t.rows(); ++r) {
    Detection d;
    d.frame = static_cast<int>(t.Number(r, frame));
    d.t_s = t.Number(r, time);
    d.source = t.Text(r, source);
    d.id = static_cast<int>(t.Number(r, id));
    d.x_m = t.Number(r, x);
    d.z_m = t.Number(r, z);
    d.range_m = t.Number(r, range);
    d.x_min_m = t.Number(r, x_min);
    d.x_max_m = t.Number(r, x_max);
    d.z_min_m = t.Number(r, z_min);
    d.z_max_m = t.Number(r, z_max);
    d.n_points = static_cast<int>(t.Number(r, n));
    out.push_back(d);
  }
  return out;
}

}  // namespace dps
