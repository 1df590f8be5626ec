#include "dps/util/csv.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>

#include "dps/util/error.h"

namespace dps {
namespace {

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    std::string cell = line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    while (!cell.empty() && (cell.back() == ' ' || cell.back() == '\r')) cell.pop_back();
    while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
    out.push_back(cell);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace

CsvTable CsvTable::Read(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(Str(path, ": cannot open file"));
  CsvTable t;
  t.path_ = path;
  std::string line;
  if (!std::getline(in, line)) throw Error(Str(path, ": empty file (expected a header row)"));
  t.header_ = Split(line);
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line == "\r") continue;
    std::vector<std::string> cells = Split(line);
    if (cells.size() != t.header_.size()) {
      throw Error(Str(path, ":", number, ": ", cells.size(), " fields, the header has ",
                      t.header_.size()));
    }
    t.cells_.push_back(std::move(cells));
  }
  return t;
}

bool CsvTable::HasColumn(const std::string& name) const {
  for (const std::string& h : header_) {
    if (h == name) return true;
  }
  return false;
}

int CsvTable::Column(const std::string& name) const {
  for (size_t i = 0; i < header_.size(); ++i) {
    if (header_[i] == name) return static_cast<int>(i);
  }
  std::string have;
  for (const std::string& h : header_) have += (have.empty() ? "" : ",") + h;
  throw Error(Str(path_, ": missing column '", name, "' (header: ", have, ")"));
}

double CsvTable::Number(size_t row, int column) const {
  const std::string& s = cells_[row][column];
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0') {
    throw Error(Str(path_, ":", Line(row), ": column '", header_[column], "': '", s,
                    "' is not a number"));
  }
  return v;
}

int CsvTable::Integer(size_t row, int column) const {
  const double v = Number(row, column);
  if (!(v >= std::numeric_limits<int>::min() && v <= std::numeric_limits<int>::max()) || v != std::floor(v)) {
    throw Error(Str(path_, ":", Line(row), ": column '", header_[column], "': '", cells_[row][column],
                    "' is not a whole number in range"));
  }
  return static_cast<int>(v);
}

}  // namespace dps
