#include "dps/calib/marks_io.h"

#include <cmath>

#include "dps/util/atomic_file.h"
#include "dps/util/csv.h"
#include "dps/util/error.h"

namespace dps {

std::vector<Mark> ReadMarks(const std::string& path) {
  const CsvTable t = CsvTable::Read(path);
  const int camera = t.Column("camera"), line = t.Column("line"), axis = t.Column("axis");
  const int u = t.Column("u"), v = t.Column("v");
  std::vector<Mark> marks;
  for (size_t r = 0; r < t.rows(); ++r) {
    Mark m;
    m.camera = t.Text(r, camera);
    m.line = t.Integer(r, line);
    const std::string& a = t.Text(r, axis);
    if (a != "X" && a != "Y" && a != "Z") {
      throw Error(Str(path, ":", t.Line(r), ": column 'axis': expected X, Y or Z, got '", a, "'"));
    }
    m.axis = a[0];
    m.u = t.Number(r, u);
    m.v = t.Number(r, v);
    if (!std::isfinite(m.u) || !std::isfinite(m.v)) throw Error(Str(path, ":", t.Line(r), ": non-finite pixel"));
    m.file_line = t.Line(r);
    marks.push_back(m);
  }
  return marks;
}

void WriteMarks(const std::vector<Mark>& marks, const std::string& path) {
  AtomicOutputFile out(path);
  out.stream().precision(10);
  out.stream() << "camera,line,axis,u,v\n";
  for (const Mark& m : marks) {
    out.stream() << m.camera << "," << m.line << "," << m.axis << "," << m.u << "," << m.v << "\n";
  }
  out.Commit();
}

}  // namespace dps
