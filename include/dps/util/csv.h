// dps — reading the project's CSV files (DESIGN.md §3): a header row, comma separators, '.'
// decimal point, no quoting; extra columns are ignored and columns are found by name.
#pragma once

#include <string>
#include <vector>

namespace dps {

class CsvTable {
 public:
  // Reads the file; throws dps::Error naming the file when it is missing, empty, or a row has a
  // different number of fields than the header.
  static CsvTable Read(const std::string& path);

  // The index of a column; throws dps::Error naming the file and the missing column.
  int Column(const std::string& name) const;
  bool HasColumn(const std::string& name) const;

  size_t rows() const { return cells_.size(); }
  const std::string& Text(size_t row, int column) const { return cells_[row][column]; }
  // A cell as a number; throws dps::Error "file:line: column 'x': 'abc' is not a number".
  double Number(size_t row, int column) const;
  // A cell as a whole number within int's range; throws dps::Error naming file, line and column
  // otherwise (a frame number of 1e300 or 2.5).
  int Integer(size_t row, int column) const;
  // The file's line number of a data row (for messages).
  int Line(size_t row) const { return static_cast<int>(row) + 2; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> cells_;
};

}  // namespace dps
