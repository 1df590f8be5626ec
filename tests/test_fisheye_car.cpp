// A check of the fisheye model on real data: the front camera of a real car
// (data/real/fisheye_car) looking at a ground mat of 40 cm squares. The calibration file's
// `project_matrix` maps the undistorted image (K with fx, fy scaled by scale_xy and cx, cy shifted
// by shift_xy) to a top-down view at 1 px = 1 cm. We build that top-down view through dps's own
// fisheye model (top-down pixel -> undistorted ray -> CameraModel::Project -> fisheye pixel) and
// check what must hold if the model is right: the mat's edges lie on a 40 px lattice, straight
// along rows and columns. A model with the distortion dropped must fail the same check.
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "check.h"
#include "dps/camera/rig_io.h"
#include "dps/util/error.h"

namespace {

constexpr double kSquarePx = 40.0;  // 40 cm squares at 1 px = 1 cm
constexpr double kPeakFraction = 0.3;  // edges: profile peaks above this fraction of the largest
constexpr double kPeriodTolPx = 1.5;     // the mat is fabric laid on paving: not exact
constexpr double kMaxFitRmsPx = 2.5;     // edges off the 40 px lattice, RMS
constexpr double kMaxStripSpreadPx = 5.0;  // one edge seen in two strips of the view
constexpr int kMinEdges = 4;             // edges seen in every strip
const cv::Size kTopDown(1200, 550);          // the front camera's top-down view

const std::string kDir = std::string(DPS_REAL_DATA_DIR) + "/fisheye_car/";

// The top-down view: every pixel traced back through the homography and the model.
cv::Mat TopDown(const cv::Mat& image, const dps::CameraModel& model, const cv::Matx33d& H,
                const cv::Matx33d& K_undistorted) {
  const cv::Matx33d back = K_undistorted.inv() * H.inv();
  cv::Mat map_x(kTopDown, CV_32F, cv::Scalar(-1)), map_y(kTopDown, CV_32F, cv::Scalar(-1));
  for (int y = 0; y < kTopDown.height; ++y) {
    for (int x = 0; x < kTopDown.width; ++x) {
      cv::Vec3d ray = back * cv::Vec3d(x, y, 1.0);
      if (ray[2] < 0) ray = -ray;  // homogeneous: any non-zero scale, the ray is in front
      Eigen::Vector2d px;
      if (ray[2] == 0 || !model.Project({ray[0], ray[1], ray[2]}, &px) || !model.InImage(px)) {
        continue;
      }
      map_x.at<float>(y, x) = static_cast<float>(px.x());
      map_y.at<float>(y, x) = static_cast<float>(px.y());
    }
  }
  cv::Mat out;
  cv::remap(image, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return out;
}

// Positions (sub-pixel) of the strong peaks of a 1-D edge profile: local maxima above half the
// largest, at least 20 px apart, refined by a parabola through the peak and its neighbours.
std::vector<double> Peaks(const cv::Mat& profile_in) {
  cv::Mat profile;
  cv::GaussianBlur(profile_in.reshape(1, 1), profile, cv::Size(5, 1), 1.0);
  const int n = profile.cols;
  double max_value = 0;
  cv::minMaxLoc(profile, nullptr, &max_value);
  std::vector<double> peaks;
  for (int i = 2; i < n - 2; ++i) {
    const double c = profile.at<double>(0, i);
    if (c < kPeakFraction * max_value) continue;
    bool is_max = true;
    for (int k = -10; k <= 10 && is_max; ++k) {
      if (k != 0 && i + k >= 0 && i + k < n && profile.at<double>(0, i + k) > c) is_max = false;
    }
    if (!is_max) continue;
    const double l = profile.at<double>(0, i - 1), r = profile.at<double>(0, i + 1);
    const double denom = l - 2 * c + r;
    peaks.push_back(i + (denom < 0 ? 0.5 * (l - r) / denom : 0.0));
  }
  return peaks;
}

// The mat's edges seen in several strips of the view: where the lines are straight, each strip
// finds the same edge positions on a 40 px lattice.
struct LatticeScore {
  int edges = 0;              // edges found in every strip
  double period_px = 0;       // least-squares lattice period
  double fit_rms_px = 0;      // RMS distance of the edges to the fitted lattice
  double strip_spread_px = 0; // largest disagreement of one edge between strips
};

LatticeScore ScoreEdges(const cv::Mat& gradient, const std::vector<cv::Rect>& strips,
                        bool along_rows) {
  std::vector<std::vector<double>> per_strip;
  for (const cv::Rect& r : strips) {
    cv::Mat profile;
    // Horizontal lines: |d/dy| summed over the strip's columns, per row; vertical lines the same
    // way round. Peak positions are relative to the strip, whose origins are shared.
    cv::reduce(cv::abs(gradient(r)), profile, along_rows ? 1 : 0, cv::REDUCE_SUM, CV_64F);
    per_strip.push_back(Peaks(profile));
  }
  LatticeScore score;
  // Edges of the first strip that every other strip also sees within 10 px.
  std::vector<double> edges;
  for (double p : per_strip[0]) {
    double lo = p, hi = p, sum = p;
    bool everywhere = true;
    for (size_t s = 1; s < per_strip.size() && everywhere; ++s) {
      double best = 1e9;
      for (double q : per_strip[s]) {
        if (std::abs(q - p) < std::abs(best - p)) best = q;
      }
      everywhere = std::abs(best - p) < 10.0;
      lo = std::min(lo, best), hi = std::max(hi, best), sum += best;
    }
    if (!everywhere) continue;
    edges.push_back(sum / per_strip.size());
    score.strip_spread_px = std::max(score.strip_spread_px, hi - lo);
  }
  score.edges = static_cast<int>(edges.size());
  if (edges.size() < 3) return score;
  // Fit p = p0 + period * k with k the lattice index of each edge.
  double sk = 0, sp = 0, skk = 0, skp = 0;
  std::vector<double> ks;
  for (double p : edges) {
    const double k = std::round((p - edges[0]) / kSquarePx);
    ks.push_back(k);
    sk += k, sp += p, skk += k * k, skp += k * p;
  }
  const double n = static_cast<double>(edges.size());
  score.period_px = (n * skp - sk * sp) / (n * skk - sk * sk);
  const double p0 = (sp - score.period_px * sk) / n;
  double ss = 0;
  for (size_t i = 0; i < edges.size(); ++i) {
    const double e = edges[i] - (p0 + score.period_px * ks[i]);
    ss += e * e;
  }
  score.fit_rms_px = std::sqrt(ss / n);
  return score;
}

struct MatScore {
  LatticeScore rows, cols;
};

MatScore ScoreTopDown(const cv::Mat& top) {
  cv::Mat grey, gx, gy;
  cv::cvtColor(top, grey, cv::COLOR_BGR2GRAY);
  cv::Sobel(grey, gx, CV_64F, 1, 0);
  cv::Sobel(grey, gy, CV_64F, 0, 1);
  // The mat lies in columns 300..900, rows 300..550 of the view (the car's body covers the
  // bottom rows; the paving around it has a finer pattern of its own). Its middle columns hold
  // circles, so horizontal lines are compared between a left and a right strip, vertical lines
  // between a near and a far one.
  const std::vector<cv::Rect> row_strips = {{320, 312, 180, 180}, {700, 312, 180, 180}};
  const std::vector<cv::Rect> col_strips = {{320, 312, 560, 90}, {320, 402, 560, 90}};
  return {ScoreEdges(gy, row_strips, true), ScoreEdges(gx, col_strips, false)};
}

void Print(const char* what, const MatScore& s) {
  std::printf("%s: rows %d edges, period %.2f px, fit rms %.2f px, strip spread %.2f px; "
              "cols %d edges, period %.2f px, fit rms %.2f px, strip spread %.2f px\n",
              what, s.rows.edges, s.rows.period_px, s.rows.fit_rms_px, s.rows.strip_spread_px,
              s.cols.edges, s.cols.period_px, s.cols.fit_rms_px, s.cols.strip_spread_px);
}

}  // namespace

int main() {
  const std::string yaml = kDir + "yaml/front.yaml";
  const dps::CameraModel model = dps::ReadOpenCVFisheye(yaml);
  CHECK_EQ(model.width(), 960);
  CHECK_EQ(model.height(), 640);
  CHECK_NEAR(model.K()(0, 0), 302.45305983229298, 1e-9);
  CHECK_NEAR(model.dist()[3], 8.4123126605702321e-03, 1e-15);

  cv::FileStorage fs(yaml, cv::FileStorage::READ);
  cv::Mat H, scale, shift;
  fs["project_matrix"] >> H;
  fs["scale_xy"] >> scale;
  fs["shift_xy"] >> shift;
  const cv::Matx33d K(model.K()(0, 0) * scale.at<float>(0), 0, model.K()(0, 2) + shift.at<float>(0),
                      0, model.K()(1, 1) * scale.at<float>(1), model.K()(1, 2) + shift.at<float>(1),
                      0, 0, 1);
  const cv::Mat image = cv::imread(kDir + "images/front.png");
  CHECK(!image.empty());
  if (image.empty()) return dps_test::Report();

  const cv::Mat top = TopDown(image, model, cv::Matx33d(H), K);
  if (const char* dump = std::getenv("DPS_TEST_DUMP")) cv::imwrite(std::string(dump) + "/front_top.png", top);
  const MatScore s = ScoreTopDown(top);
  Print("dps fisheye model", s);
  for (const LatticeScore& l : {s.rows, s.cols}) {
    CHECK(l.edges >= kMinEdges);
    CHECK_NEAR(l.period_px, kSquarePx, kPeriodTolPx);
    CHECK(l.fit_rms_px < kMaxFitRmsPx);
  }
  CHECK(s.rows.strip_spread_px < kMaxStripSpreadPx);

  // Negative control: the same lens without its distortion terms bends the mat's lines off the
  // lattice, so this check can fail.
  const auto plain = dps::CameraModel::Fisheye(960, 640, model.K(), {0, 0, 0, 0});
  const MatScore w = ScoreTopDown(TopDown(image, plain, cv::Matx33d(H), K));
  Print("same lens, no distortion", w);
  CHECK(w.cols.fit_rms_px > kMaxFitRmsPx || w.rows.strip_spread_px > kMaxStripSpreadPx);
  return dps_test::Report();
}
