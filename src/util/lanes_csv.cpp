#include "dps/util/lanes_csv.h"

#include "dps/util/atomic_file.h"
#include "dps/util/csv.h"
#include "dps/util/error.h"

namespace dps {
namespace {

// A cell that must be one of `names`.
const std::string& OneOf(const CsvTable& t, size_t row, int column, const std::string& field,
                         std::initializer_list<const char*> names) {
  const std::string& v = t.Text(row, column);
  for (const char* n : names) {
    if (v == n) return v;
  }
  std::string expected;
  for (const char* n : names) expected += (expected.empty() ? "" : ", ") + std::string(*n ? n : "(empty)");
  throw Error(Str(t.path(), ":", t.Line(row), ": column '", field, "': '", v, "' is not one of ", expected));
}

}  // namespace

void WriteLaneBoundaries(const std::vector<LaneBoundaryRow>& rows, const std::string& path) {
  AtomicOutputFile out(path);
  out.stream().precision(9);
  out.stream() << "frame,t,boundary,offset,heading_deg,curvature,type,confidence\n";
  for (const LaneBoundaryRow& r : rows) {
    out.stream() << r.frame << ',' << r.t_s << ',' << r.boundary << ',' << r.offset_m + 0.0 << ',' << r.heading_deg + 0.0 << ','
                 << r.curvature << ',' << r.type << ',' << r.confidence << '\n';
  }
  out.Commit();
}

std::vector<LaneBoundaryRow> ReadLaneBoundaries(const std::string& path) {
  const CsvTable t = CsvTable::Read(path);
  const int frame = t.Column("frame"), time = t.Column("t"), boundary = t.Column("boundary"), offset = t.Column("offset");
  const int heading = t.Column("heading_deg"), curvature = t.Column("curvature"), type = t.Column("type");
  const int confidence = t.Column("confidence");
  std::vector<LaneBoundaryRow> out;
  for (size_t r = 0; r < t.rows(); ++r) {
    LaneBoundaryRow row{t.Integer(r, frame), t.Number(r, time),
                        OneOf(t, r, boundary, "boundary", {"left2", "left", "right", "right2"}),
                        t.Number(r, offset), t.Number(r, heading), t.Number(r, curvature),
                        OneOf(t, r, type, "type", {"solid", "dashed"}), t.Number(r, confidence)};
    if (!(row.confidence >= 0 && row.confidence <= 1)) {
      throw Error(Str(path, ":", t.Line(r), ": column 'confidence': ", row.confidence, " is not within 0..1"));
    }
    out.push_back(row);
  }
  return out;
}

void WriteEgoLane(const std::vector<EgoLaneRow>& rows, const std::string& path) {
  AtomicOutputFile out(path);
  out.stream().precision(9);
  out.stream() << "frame,t,lp,lane_width,heading_deg,event\n";
  for (const EgoLaneRow& r : rows) {
    out.stream() << r.frame << ',' << r.t_s << ',' << r.lp_m + 0.0 << ',' << r.lane_width_m << ',' << r.heading_deg << ','
                 << r.event << '\n';
  }
  out.Commit();
}

std::vector<EgoLaneRow> ReadEgoLane(const std::string& path) {
  const CsvTable t = CsvTable::Read(path);
  const int frame = t.Column("frame"), time = t.Column("t"), lp = t.Column("lp"), width = t.Column("lane_width");
  const int heading = t.Column("heading_deg"), event = t.Column("event");
  std::vector<EgoLaneRow> out;
  for (size_t r = 0; r < t.rows(); ++r) {
    out.push_back({t.Integer(r, frame), t.Number(r, time), t.Number(r, lp), t.Number(r, width), t.Number(r, heading),
                   OneOf(t, r, event, "event", {"", "left", "right"})});
  }
  return out;
}

}  // namespace dps
