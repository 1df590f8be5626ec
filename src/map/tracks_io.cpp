#include "dps/map/tracks_io.h"

#include "dps/detect/object_attributes.h"
#include "dps/util/atomic_file.h"
#include "dps/util/csv.h"

namespace dps {

void WriteTracks(const std::vector<TrackState>& tracks, const std::string& path) {
  AtomicOutputFile out(path);
  out.stream().precision(6);
  out.stream() << std::fixed << "frame,t,track,x,z,vx,vz,sigma_x,sigma_z,age,length,width,height,lane,class\n";
  for (const TrackState& t : tracks) {
    if (!t.confirmed) continue;
    out.stream() << t.frame << "," << t.t_s << "," << t.id << "," << t.x_m << "," << t.z_m << "," << t.vx_mps << ","
                 << t.vz_mps << "," << t.sigma_x_m << "," << t.sigma_z_m << "," << t.age << "," << t.length_m << ","
                 << t.width_m << "," << AttributeCells(t.height_m, t.lane, t.object_class) << "\n";
  }
  out.Commit();
}

std::vector<TrackState> ReadTracks(const std::string& path) {
  const CsvTable t = CsvTable::Read(path);
  const int frame = t.Column("frame"), time = t.Column("t"), id = t.Column("track"), x = t.Column("x"),
            z = t.Column("z"), vx = t.Column("vx"), vz = t.Column("vz"), sx = t.Column("sigma_x"),
            sz = t.Column("sigma_z"), age = t.Column("age");
  // Extra columns (not in DESIGN.md §3.5; files of other writers may lack them).
  const int length = t.HasColumn("length") ? t.Column("length") : -1;
  const int width = t.HasColumn("width") ? t.Column("width") : -1;
  const AttributeColumns attributes(t);
  std::vector<TrackState> out;
  for (size_t r = 0; r < t.rows(); ++r) {
    TrackState s;
    s.frame = t.Integer(r, frame);
    s.t_s = t.Number(r, time);
    s.id = t.Integer(r, id);
    s.x_m = t.Number(r, x);
    s.z_m = t.Number(r, z);
    s.vx_mps = t.Number(r, vx);
    s.vz_mps = t.Number(r, vz);
    s.sigma_x_m = t.Number(r, sx);
    s.sigma_z_m = t.Number(r, sz);
    s.age = t.Integer(r, age);
    if (length >= 0) s.length_m = t.Number(r, length);
    if (width >= 0) s.width_m = t.Number(r, width);
    ReadAttributes(t, r, attributes, &s.height_m, &s.lane, &s.object_class);
    s.confirmed = true;
    out.push_back(s);
  }
  return out;
}

}  // namespace dps
