#include "dps/detect/disparity_histogram.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "dps/stereo/sad_stereo.h"
#include "dps/util/error.h"

namespace dps {
void HistogramOptions::Check() const {
  const OptionCheck Require("histogram");
  Require(max_disparity > min_disparity, "max_disparity", max_disparity, "> min_disparity");
  Require(bin_px > 0, "bin_px", bin_px, "> 0");
  Require(score_ramp_px > 0, "score_ramp_px", score_ramp_px, "> 0");
  Require(smooth_sigma >= 0, "smooth_sigma", smooth_sigma, ">= 0");
  Require(close_width >= 1 && close_width % 2 == 1, "close_width", close_width, "odd, >= 1");
  Require(close_height >= 1 && close_height % 2 == 1, "close_height", close_height, "odd, >= 1");
  Require(threshold > 0, "threshold", threshold, "> 0");
  Require(far_reference_px >= 0, "far_reference_px", far_reference_px, ">= 0");
  Require(far_min_fraction > 0 && far_min_fraction <= 1, "far_min_fraction", far_min_fraction, "in (0, 1]");
  Require(far_clearance_columns >= 1 && far_clearance_columns % 2 == 1, "far_clearance_columns",
          far_clearance_columns, "odd, >= 1");
  Require(min_columns >= 1, "min_columns", min_columns, ">= 1");
  Require(min_votes >= 0, "min_votes", min_votes, ">= 0");
  Require(link_max_gap >= 0, "link_max_gap", link_max_gap, ">= 0");
  Require(link_max_depth_ratio >= 1, "link_max_depth_ratio", link_max_depth_ratio, ">= 1");
  Require(link_margin_px >= 0, "link_margin_px", link_margin_px, ">= 0");
  Require(link_max_see_through >= 0, "link_max_see_through", link_max_see_through, ">= 0");
  Require(link_fit_columns >= 0, "link_fit_columns", link_fit_columns, ">= 0");
  Require(link_line_max_gap >= 0, "link_line_max_gap", link_line_max_gap, ">= 0");
}

int HistogramOptions::bins() const {
  return std::max(1, static_cast<int>(std::ceil((max_disparity - min_disparity) / bin_px)));
}

cv::Mat RoadRamp(const cv::Mat& road, int rows) {
  cv::Mat ramp(road.size(), CV_32F, cv::Scalar(0));
  for (int y = 0; y < road.rows; ++y) {
    const int below = std::min(road.rows - 1, y + rows);
    for (int x = 0; x < road.cols; ++x) {
      const float a = road.at<float>(y, x), b = road.at<float>(below, x);
      if (std::isfinite(a) && std::isfinite(b)) ramp.at<float>(y, x) = std::max(0.0f, b - a);
      else if (std::isfinite(b)) ramp.at<float>(y, x) = b;  // at the horizon
    }
  }
  return ramp;
}

cv::Mat ScoreImage(const cv::Mat& disparity, const cv::Mat& road, const HistogramOptions& o, const cv::Mat& ramp) {
  CV_Assert(disparity.type() == CV_32F && road.type() == CV_32F && disparity.size() == road.size());
  CV_Assert(ramp.empty() || (ramp.type() == CV_32F && ramp.size() == road.size()));
  cv::Mat score(disparity.size(), CV_32F);
  for (int y = 0; y < disparity.rows; ++y) {
    const float* d = disparity.ptr<float>(y);
    const float* r = road.ptr<float>(y);
    float* s = score.ptr<float>(y);
    const float* t = ramp.empty() ? nullptr : ramp.ptr<float>(y);
    for (int x = 0; x < disparity.cols; ++x) {
      if (!std::isfinite(d[x])) {
        s[x] = 0.0f;
        continue;
      }
      const float base = std::isfinite(r[x]) ? r[x] : 0.0f;
      const float diff = o.two_sided ? std::abs(d[x] - base) : d[x] - base;
      const double T = t ? std::max<double>(o.score_ramp_px, t[x]) : o.score_ramp_px;
      s[x] = static_cast<float>(std::clamp(diff / T, 0.0, 1.0));  // eq. 14
    }
  }
  return score;
}

cv::Mat ColumnHistogram(const cv::Mat& disparity, const cv::Mat& score, const HistogramOptions& o,
                        cv::Mat* moments) {
  CV_Assert(disparity.type() == CV_32F && score.type() == CV_32F && disparity.size() == score.size());
  const int bins = o.bins();
  cv::Mat hist(bins, disparity.cols, CV_32F, cv::Scalar(0));
  cv::Mat moment(bins, disparity.cols, CV_32F, cv::Scalar(0));
  for (int y = 0; y < disparity.rows; ++y) {
    const float* d = disparity.ptr<float>(y);
    const float* s = score.ptr<float>(y);
    for (int x = 0; x < disparity.cols; ++x) {
      if (s[x] <= 0.0f) continue;
      const int bin = static_cast<int>(std::floor((d[x] - o.min_disparity) / o.bin_px));
      if (bin < 0 || bin >= bins) continue;
      hist.at<float>(bin, x) += s[x];  // eq. 15
      moment.at<float>(bin, x) += s[x] * d[x];
    }
  }
  if (moments) *moments = moment;
  return hist;
}

std::vector<HistogramComponent> FindComponents(const cv::Mat& histogram, const HistogramOptions& o,
                                               cv::Mat* labels_out, const cv::Mat& moments) {
  CV_Assert(moments.empty() || (moments.type() == CV_32F && moments.size() == histogram.size()));
  o.Check();
  cv::Mat smooth = histogram.clone();
  if (o.smooth_sigma > 0) cv::GaussianBlur(histogram, smooth, cv::Size(), o.smooth_sigma, o.smooth_sigma);
  cv::morphologyEx(smooth, smooth, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(o.close_width, o.close_height)));
  cv::Mat mask = smooth >= o.threshold;
  if (o.far_reference_px > 0) {
    // Per bin its own threshold (a plain loop: one cv::compare per bin cost more in calls than
    // in comparing), in float as cv::compare would.
    cv::Mat far(smooth.size(), CV_8U), clear;
    for (int b = 0; b < smooth.rows; ++b) {
      const double fraction = std::clamp(BinDisparity(o, b) / o.far_reference_px, o.far_min_fraction, 1.0);
      const float threshold = static_cast<float>(o.threshold * fraction);
      const float* s = smooth.ptr<float>(b);
      std::uint8_t* f = far.ptr<std::uint8_t>(b);
      for (int x = 0; x < smooth.cols; ++x) f[x] = s[x] >= threshold ? 255 : 0;
    }
    cv::dilate(mask, clear, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(o.far_clearance_columns, 3)));
    mask |= far & ~clear;
  }
  cv::Mat labels;
  const int count = cv::connectedComponents(mask, labels, 8, CV_32S);
  // Each label's columns, in one pass.
  std::vector<int> first(count, histogram.cols), end(count, 0);
  for (int b = 0; b < histogram.rows; ++b) {
    const int* row = labels.ptr<int>(b);
    for (int x = 0; x < histogram.cols; ++x) {
      if (row[x] == 0) continue;
      first[row[x]] = std::min(first[row[x]], x);
      end[row[x]] = std::max(end[row[x]], x + 1);
    }
  }
  std::vector<HistogramComponent> components;
  for (int label = 1; label < count; ++label) {
    HistogramComponent c;
    c.label = label;
    c.x_begin = first[label];
    c.x_end = end[label];
    if (c.x_end - c.x_begin < o.min_columns) continue;
    // Centroid of the raw histogram within the component, per column (step 4).
    c.column_disparity.assign(c.x_end - c.x_begin, kInvalidDisparity);
    for (int x = c.x_begin; x < c.x_end; ++x) {
      double mass = 0.0, moment = 0.0;
      for (int b = 0; b < histogram.rows; ++b) {
        if (labels.at<int>(b, x) != label) continue;
        const double h = histogram.at<float>(b, x);
        mass += h;
        moment += moments.empty() ? h * BinDisparity(o, b) : moments.at<float>(b, x);
      }
      if (mass > 0) c.column_disparity[x - c.x_begin] = static_cast<float>(moment / mass);
      c.votes += mass;
    }
    if (c.votes < o.min_votes) continue;
    components.push_back(std::move(c));
  }
  if (labels_out) *labels_out = labels;
  return components;
}

std::pair<int, int> ProjectedColumns(const HistogramComponent& c, int trim) {
  int first = c.x_end, last = c.x_begin - 1;
  for (int x = c.x_begin; x < c.x_end; ++x) {
    if (!std::isfinite(c.column_disparity[x - c.x_begin])) continue;
    first = std::min(first, x);
    last = std::max(last, x);
  }
  if (trim > 0 && last - first + 1 > 2 * trim + 1) {
    first += trim;
    last -= trim;
  }
  return {first, last};
}

namespace {

// The first (or last) finite column disparity of a component; NaN if none.
float EndDisparity(const HistogramComponent& c, bool last) {
  const std::vector<float>& d = c.column_disparity;
  for (size_t i = 0; i < d.size(); ++i) {
    const float v = d[last ? d.size() - 1 - i : i];
    if (std::isfinite(v)) return v;
  }
  return std::numeric_limits<float>::quiet_NaN();
}

// The (column, disparity) pairs of the last (`last`) or first `n` columns of a component with a
// centroid.
std::vector<cv::Point2d> EndColumns(const HistogramComponent& c, bool last, int n) {
  std::vector<cv::Point2d> out;
  const std::vector<float>& d = c.column_disparity;
  for (size_t i = 0; i < d.size() && static_cast<int>(out.size()) < n; ++i) {
    const size_t at = last ? d.size() - 1 - i : i;
    if (std::isfinite(d[at])) out.emplace_back(c.x_begin + static_cast<double>(at), d[at]);
  }
  return out;
}

// Whether the ends of two components close side by side (at most link_line_max_gap columns
// apart) continue one surface: they meet (their end disparities agree, as at a corner of a car),
// or they lie on one plane — a plane's disparity is linear along a row, so the line fitted to
// either part's columns (up to link_fit_columns from its end), carried across the gap, meets the
// other part's end — within link_margin_px or 10 %. Parts with fewer than 3 such columns pass the
// second test; parts further apart pass (a line carried across a long untextured stretch is too
// uncertain to judge by).
bool OnOneSurface(const HistogramComponent& a, const HistogramComponent& b, float da, float db,
                  const HistogramOptions& o) {
  if (o.link_fit_columns == 0 || b.x_begin - a.x_end > o.link_line_max_gap) return true;
  const double tolerance = std::max(o.link_margin_px, 0.1 * std::min(da, db));
  if (std::abs(da - db) <= tolerance) return true;
  bool fitted = false;
  for (const bool from_a : {true, false}) {
    const std::vector<cv::Point2d> p = EndColumns(from_a ? a : b, from_a, o.link_fit_columns);
    if (p.size() < 3) continue;
    fitted = true;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const cv::Point2d& q : p) sx += q.x, sy += q.y, sxx += q.x * q.x, sxy += q.x * q.y;
    const double n = static_cast<double>(p.size());
    const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx), offset = (sy - slope * sx) / n;
    const double predicted = from_a ? slope * b.x_begin + offset : slope * (a.x_end - 1) + offset;
    if (std::abs(predicted - (from_a ? db : da)) <= tolerance) return true;
  }
  return !fitted;
}

// Pixels in columns [x0, x1) that see something farther than the line from (x0 - 1, d0) to
// (x1, d1): valid disparity below the line's by the margin, on rows where the road lies beyond it.
int SeeThrough(const cv::Mat& disparity, const cv::Mat& road, int x0, int x1, float d0, float d1,
               const HistogramOptions& o) {
  int count = 0;
  for (int x = x0; x < x1; ++x) {
    const double line = d0 + (d1 - d0) * (x - x0 + 1.0) / (x1 - x0 + 1.0);
    const double farther = line - std::max(o.link_margin_px, 0.1 * line);
    for (int y = 0; y < disparity.rows; ++y) {
      const float v = disparity.at<float>(y, x), r = road.at<float>(y, x);
      count += std::isfinite(v) && std::isfinite(r) && r < line && v < farther;
    }
  }
  return count;
}

}  // namespace

std::vector<HistogramComponent> LinkComponents(std::vector<HistogramComponent> cs, const cv::Mat& disparity,
                                               const cv::Mat& road, const HistogramOptions& o, cv::Mat* labels,
                                               const LinkVeto& allow) {
  CV_Assert(disparity.type() == CV_32F && road.type() == CV_32F && disparity.size() == road.size());
  o.Check();
  if (o.link_max_gap == 0 || cs.size() < 2) return cs;
  std::sort(cs.begin(), cs.end(), [](const HistogramComponent& a, const HistogramComponent& b) {
    return a.x_begin < b.x_begin;
  });
  std::vector<HistogramComponent> out;
  std::vector<bool> used(cs.size(), false);
  for (size_t i = 0; i < cs.size(); ++i) {
    if (used[i]) continue;
    HistogramComponent a = cs[i];
    used[i] = true;
    // Grow to the right while the nearest disjoint neighbour within the gap qualifies.
    for (bool grown = true; grown;) {
      grown = false;
      const float da = EndDisparity(a, true);
      if (!std::isfinite(da) || da <= 0) break;
      size_t best = cs.size();
      for (size_t j = 0; j < cs.size(); ++j) {
        if (used[j] || cs[j].x_begin < a.x_end || cs[j].x_begin - a.x_end > o.link_max_gap) continue;
        if (best == cs.size() || cs[j].x_begin < cs[best].x_begin) best = j;
      }
      if (best == cs.size()) break;
      const HistogramComponent& b = cs[best];
      const float db = EndDisparity(b, false);
      if (!std::isfinite(db) || db <= 0 || std::max(da, db) > o.link_max_depth_ratio * std::min(da, db)) break;
      if (allow && !allow(a, a.x_end - 1, da, b, b.x_begin, db)) break;
      if (SeeThrough(disparity, road, a.x_end, b.x_begin, da, db, o) > o.link_max_see_through) break;
      if (!OnOneSurface(a, b, da, db, o)) break;
      a.column_disparity.resize(b.x_begin - a.x_begin, kInvalidDisparity);
      a.column_disparity.insert(a.column_disparity.end(), b.column_disparity.begin(), b.column_disparity.end());
      a.x_end = b.x_end;
      a.votes += b.votes;
      if (labels) labels->setTo(a.label, *labels == b.label);
      used[best] = true;
      grown = true;
    }
    out.push_back(std::move(a));
  }
  return out;
}

std::pair<int, int> ValidColumns(const cv::Mat& disparity) {
  CV_Assert(disparity.type() == CV_32F);
  // Each row only needs looking at up to the first (from its last) valid column found so far.
  int first = disparity.cols, last = -1;
  for (int y = 0; y < disparity.rows; ++y) {
    const float* d = disparity.ptr<float>(y);
    for (int x = 0; x < first; ++x) {
      if (d[x] < kInvalidDisparity) {
        first = x;
        break;
      }
    }
    for (int x = disparity.cols - 1; x > last; --x) {
      if (d[x] < kInvalidDisparity) {
        last = x;
        break;
      }
    }
  }
  return {first, last};
}

}  // namespace dps
