// Internal: reading typed fields of cv::FileStorage nodes with one-line errors that name the file
// and the field. Shared by the readers of rig.yaml, scene files and OpenCV calibration files.
#pragma once

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "dps/util/error.h"

namespace dps {
namespace internal {

// One line of an OpenCV error, without OpenCV's own "file:line: error: (-2:...)" prefix noise.
inline std::string OneLine(const cv::Exception& e) {
  std::string msg = e.err.empty() ? e.what() : e.err;
  for (char& c : msg) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return msg;
}

// Opens `path` for reading; throws dps::Error naming the file when OpenCV's parser does not finish
// on it within `seconds` (some malformed files make it loop forever) or fails on it.
cv::FileStorage OpenWithin(const std::string& path, double seconds);

inline cv::FileStorage OpenForReading(const std::string& path) {
  std::error_code error;  // e.g. a name too long for the file system: not found either
  if (!std::filesystem::exists(path, error)) throw Error(Str(path, ": file not found"));
  cv::FileStorage fs;
  try {
    fs = OpenWithin(path, 10.0);
  } catch (const Error&) {
    throw;
  } catch (const cv::Exception& e) {
    throw Error(Str(path, ": not a valid OpenCV YAML/XML file: ", OneLine(e)));
  } catch (const std::exception& e) {  // OpenCV's parser lets e.g. std::length_error out
    throw Error(Str(path, ": not a valid OpenCV YAML/XML file (", e.what(), ")"));
  }
  if (!fs.isOpened()) throw Error(Str(path, ": cannot open as an OpenCV YAML/XML file"));
  return fs;
}

// Reads fields of one node, prefixing every error with `where` ("rig.yaml: camera 'left'").
class FieldReader {
 public:
  FieldReader(const cv::FileNode& node, std::string where)
      : node_(node), where_(std::move(where)) {}

  // (cv::FileNode::operator[] asserts on a node that is not a map: such a node has no fields.)
  bool Has(const std::string& key) const { return node_.isMap() && !node_[key].empty(); }

  [[noreturn]] void Fail(const std::string& key, const std::string& problem) const {
    throw Error(Str(where_, ": field '", key, "': ", problem));
  }

  cv::FileNode Required(const std::string& key) const {
    if (!node_.isMap()) throw Error(Str(where_, ": expected a map of fields (looking for '", key, "')"));
    cv::FileNode n = node_[key];
    if (n.empty()) Fail(key, "missing");
    return n;
  }

  double Number(const std::string& key) const {
    const cv::FileNode n = Required(key);
    if (!n.isReal() && !n.isInt()) Fail(key, "expected a number");
    const double v = static_cast<double>(n);
    if (!std::isfinite(v)) Fail(key, "expected a finite number");
    return v;
  }

  double NumberOr(const std::string& key, double fallback) const {
    return Has(key) ? Number(key) : fallback;
  }

  int Integer(const std::string& key) const {
    const cv::FileNode n = Required(key);
    if (!n.isInt()) Fail(key, "expected an integer");
    return static_cast<int>(n);
  }

  int IntegerOr(const std::string& key, int fallback) const {
    return Has(key) ? Integer(key) : fallback;
  }

  std::string TextOr(const std::string& key, const std::string& fallback) const {
    return Has(key) ? Text(key) : fallback;
  }

  // A sub-reader for a nested map or list item, with `where` extended by `label`.
  FieldReader Child(const cv::FileNode& node, const std::string& label) const {
    return FieldReader(node, where_ + ": " + label);
  }

  const cv::FileNode& node() const { return node_; }

  std::string Text(const std::string& key) const {
    const cv::FileNode n = Required(key);
    if (!n.isString()) Fail(key, "expected a string");
    return static_cast<std::string>(n);
  }

  // A matrix as !!opencv-matrix or as a plain list (row-major); `rows` x `cols` expected.
  Eigen::MatrixXd Matrix(const std::string& key, int rows, int cols) const {
    const cv::FileNode n = Required(key);
    std::vector<double> values;
    int got_rows = 0;
    int got_cols = 0;
    if (n.isSeq()) {
      for (const cv::FileNode& item : n) {
        if (!item.isReal() && !item.isInt()) Fail(key, "expected a list of numbers");
        values.push_back(static_cast<double>(item));
      }
      got_rows = static_cast<int>(values.size());
      got_cols = 1;
      if (static_cast<int>(values.size()) == rows * cols) {
        got_rows = rows;
        got_cols = cols;
      }
    } else if (n.isMap()) {
      // The size it claims, checked before OpenCV allocates it (a small file may ask for gigabytes).
      const cv::FileNode nr = n["rows"], nc = n["cols"];
      if (!nr.isInt() || !nc.isInt()) Fail(key, "an !!opencv-matrix needs integer rows and cols");
      const long claimed = static_cast<long>(static_cast<int>(nr)) * static_cast<int>(nc);
      if (claimed != static_cast<long>(rows) * cols) {
        Fail(key, Str("expected a ", rows, "x", cols, " matrix, got ", static_cast<int>(nr), "x", static_cast<int>(nc)));
      }
      cv::Mat m;
      try {
        n >> m;
      } catch (const cv::Exception& e) {
        Fail(key, "not a readable !!opencv-matrix: " + OneLine(e));
      }
      if (m.empty()) Fail(key, "expected an !!opencv-matrix or a list of numbers");
      m.convertTo(m, CV_64F);
      got_rows = m.rows;
      got_cols = m.cols;
      // A vector may be stored as a row or a column.
      if ((rows == 1 || cols == 1) && static_cast<int>(m.total()) == rows * cols) {
        got_rows = rows;
        got_cols = cols;
      }
      values.assign(m.begin<double>(), m.end<double>());
    } else {
      Fail(key, "expected an !!opencv-matrix or a list of numbers");
    }
    if (got_rows != rows || got_cols != cols) {
      Fail(key, Str("expected a ", rows, "x", cols, " matrix, got ", got_rows, "x", got_cols));
    }
    Eigen::MatrixXd out(rows, cols);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        out(r, c) = values[r * cols + c];
        if (!std::isfinite(out(r, c))) Fail(key, "has a non-finite entry");
      }
    }
    return out;
  }

  // A plain list of min_size .. max_size finite numbers.
  std::vector<double> List(const std::string& key, size_t min_size, size_t max_size) const {
    const cv::FileNode n = Required(key);
    if (!n.isSeq()) Fail(key, "expected a list of numbers");
    if (n.size() < min_size || n.size() > max_size) {
      Fail(key, Str("expected ", min_size, " to ", max_size, " numbers, got ", n.size()));
    }
    std::vector<double> values;
    for (const cv::FileNode& item : n) {
      if (!item.isReal() && !item.isInt()) Fail(key, "expected a list of numbers");
      values.push_back(static_cast<double>(item));
      if (!std::isfinite(values.back())) Fail(key, "has a non-finite entry");
    }
    return values;
  }

  const std::string& where() const { return where_; }

 private:
  cv::FileNode node_;
  std::string where_;
};

}  // namespace internal
}  // namespace dps
