#include "dps/synth/truth_io.h"

#include "dps/util/atomic_file.h"
#include "dps/util/csv.h"

namespace dps {

void WriteTruth(const std::vector<TruthRow>& rows, const std::string& path) {
  AtomicOutputFile out(path);
  out.stream() << "frame,t,id,kind,x,z,heading_deg,length,width,height,vx,vz\n";
  for (const TruthRow& r : rows) {
    out.stream() << r.frame << "," << r.t_s << "," << r.id << "," << r.kind << "," << r.x_m << "," << r.z_m
                 << "," << r.heading_deg << "," << r.length_m << "," << r.width_m << "," << r.height_m << ","
                 << r.vx_mps << "," << r.vz_mps << "\n";
  }
  out.Commit();
}

std::vector<TruthRow> ReadTruth(const std::string& path) {
  const CsvTable t = CsvTable::Read(path);
  const int frame = t.Column("frame"), time = t.Column("t"), id = t.Column("id"), kind = t.Column("kind");
  const int x = t.Column("x"), z = t.Column("z"), heading = t.Column("heading_deg");
  const int length = t.Column("length"), width = t.Column("width"), height = t.Column("height");
  const int vx = t.Column("vx"), vz = t.Column("vz");
  std::vector<TruthRow> out;
  for (size_t r = 0; r < t.rows(); ++r) {
    out.push_back({t.Integer(r, frame), t.Number(r, time), t.Integer(r, id),
                   t.Text(r, kind), t.Number(r, x), t.Number(r, z), t.Number(r, heading), t.Number(r, length),
                   t.Number(r, width), t.Number(r, height), t.Number(r, vx), t.Number(r, vz)});
  }
  return out;
}

}  // namespace dps
