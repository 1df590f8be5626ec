#include "dps/disparity_histogram.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "dps/error.h"
#include "dps/sad_stereo.h"

namespace dps {
namespace {

void Require(bool ok, const char* field, double value, const char* constraint) {
  if (!ok) throw Error(Str("histogram option ", field, " = ", value, ": violated constraint ", constraint));
}

}  // namespace

void HistogramOptions::Check() const {
  Require(max_disparity > min_disparity, "max_disparity", max_disparity, "> min_disparity");
  Require(bin_px > 0, "bin_px", bin_px, "> 0");
  Require(score_ramp_px > 0, "score_ramp_px", score_ramp_px, "> 0");
  Require(smooth_sigma >= 0, "smooth_sigma", smooth_sigma, ">= 0");
  Require(close_width >= 1 && close_width % 2 == 1, "close_width", close_width, "odd, >= 1");
  Require(close_height >= 1 && close_height % 2 == 1, "close_height", close_height, "odd, >= 1");
  Require(threshold > 0, "threshold", threshold, "> 0");
  Require(min_columns >= 1, "min_columns", min_columns, ">= 1");
  Require(min_votes >= 0, "min_votes", min_votes, ">= 0");
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
  cv::Mat labels;
  const int count = cv::connectedComponents(mask, labels, 8, CV_32S);
  std::vector<HistogramComponent> components;
  for (int label = 1; label < count; ++label) {
    HistogramComponent c;
    c.label = label;
    c.x_begin = histogram.cols;
    c.x_end = 0;
    for (int x = 0; x < histogram.cols; ++x) {
      for (int b = 0; b < histogram.rows; ++b) {
        if (labels.at<int>(b, x) == label) {
          c.x_begin = std::min(c.x_begin, x);
          c.x_end = std::max(c.x_end, x + 1);
        }
      }
    }
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

}  // namespace dps
