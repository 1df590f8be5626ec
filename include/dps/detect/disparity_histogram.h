// dps — column disparity histograms and their obstacle components
// (Gandhi & Trivedi 2006, eq. 14-15; conference version eq. 6-7).
//
// Pixels of an obstacle at one distance share one disparity, so in each image column they pile
// up in one histogram bin, while the road spreads over the disparities of its rows. Steps:
// 1. score(x, y) (eq. 14): how far the pixel's disparity lies above the road's disparity d_bg at
//    that pixel, 0 at or below the road, 1 at d_bg + T or more, linear in between. Side views use
//    the distance from the road's disparity either way (independently moving vehicles can appear
//    with smaller disparity than the road).
// 2. hist(d, x) (eq. 15): per column, the scores summed by disparity bin.
// 3. Gaussian smoothing and a morphological closing, a threshold, connected components.
// 4. The obstacle image: for each component and column, the centroid disparity of the column's
//    histogram within the component (sub-pixel).
// Conventions: the histogram image has one row per disparity bin (row = (d - min) / bin) and one
// column per image column; disparities as in sad_stereo.h (kInvalidDisparity = none).
#pragma once

#include <functional>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace dps {

struct HistogramOptions {
  double min_disparity = 0.0;      // first bin's lower edge, px
  double max_disparity = 64.0;     // last bin's upper edge, px, > min
  double bin_px = 1.0;             // bin width, px, > 0
  double score_ramp_px = 2.0;      // T of eq. 14, px, > 0
  bool two_sided = false;          // score |d - d_bg| (side views) instead of d - d_bg
  double smooth_sigma = 1.0;       // Gaussian smoothing of the histogram, bins/columns, >= 0
  int close_width = 5;             // morphological closing, columns (odd, >= 1)
  int close_height = 3;            // ... and bins (odd, >= 1)
  double threshold = 4.0;          // votes a smoothed bin needs, > 0
  // Far obstacles cover fewer rows (rows ~ height x d / B), so bins below far_reference_px need
  // fewer votes: threshold x max(far_min_fraction, d / far_reference_px) — only where the full
  // threshold found nothing within far_clearance_columns columns and one bin (else the edges of
  // near components fatten). far_reference_px = 0: one threshold for all bins.
  double far_reference_px = 0.0;  // >= 0
  double far_min_fraction = 0.4;  // (0, 1]
  int far_clearance_columns = 15; // odd, >= 1
  int min_columns = 3;             // narrower components are dropped, >= 1
  double min_votes = 30.0;         // components with fewer votes in all are dropped, >= 0
  // Linking (LinkComponents): side-by-side components at most link_max_gap columns apart, whose
  // depths differ by at most the factor link_max_depth_ratio, with at most link_max_see_through
  // pixels in the gap that show something farther (by link_margin_px or 10 %). 0 = no linking.
  int link_max_gap = 0;
  double link_max_depth_ratio = 1.6;
  double link_margin_px = 2.0;
  int link_max_see_through = 5;
  // ... and, when at most link_line_max_gap columns apart, whose ends meet or lie on one plane:
  // the line through either's link_fit_columns end column disparities, carried across the gap,
  // meets the other's end (link_fit_columns = 0: no such test).
  int link_fit_columns = 12;
  int link_line_max_gap = 4;

  // Throws dps::Error naming the field and the violated constraint.
  void Check() const;
  int bins() const;
};

// The score image (CV_32F, 0..1) of eq. 14 for a disparity image and the road's disparity at
// each pixel (CV_32F; kInvalidDisparity where the pixel sees no road, e.g. above the horizon,
// which counts as road disparity 0). `ramp` (optional, CV_32F, px) replaces T per pixel where it
// is larger than options.score_ramp_px: block matching smears the road's disparity over the
// window's rows, so T must cover the road's disparity change across half a window.
cv::Mat ScoreImage(const cv::Mat& disparity, const cv::Mat& road_disparity, const HistogramOptions& options,
                   const cv::Mat& ramp = cv::Mat());

// The per-pixel ramp for ScoreImage: the road's disparity change over `rows` rows below each
// pixel (CV_32F; 0 where there is no road).
cv::Mat RoadRamp(const cv::Mat& road_disparity, int rows);

// The column histogram (eq. 15): CV_32F, options.bins() rows x disparity.cols columns.
// `moments` (optional) receives the same sums weighted by the disparities themselves, so that
// centroids are exact rather than bin centres.
cv::Mat ColumnHistogram(const cv::Mat& disparity, const cv::Mat& score, const HistogramOptions& options,
                        cv::Mat* moments = nullptr);

// One obstacle component of the histogram.
struct HistogramComponent {
  int label = 0;
  int x_begin = 0, x_end = 0;          // columns [x_begin, x_end)
  std::vector<float> column_disparity; // centroid disparity per column (kInvalidDisparity = none)
  double votes = 0.0;                  // histogram mass inside the component
};

// Steps 3-4: smoothing, closing, threshold, components, centroids (from `moments` when given,
// else from bin centres). `labels` (optional) receives the component label image (CV_32S,
// histogram size, 0 = background).
std::vector<HistogramComponent> FindComponents(const cv::Mat& histogram, const HistogramOptions& options,
                                               cv::Mat* labels = nullptr, const cv::Mat& moments = cv::Mat());

// One surface often falls apart into several components: a car's side seen at a grazing angle
// has stretches without texture, and the histogram loses them. Two components side by side are
// parts of one surface when, in the columns between them, nothing farther than the line joining
// their ends is seen: a real gap between two objects shows the road or whatever lies behind it
// (valid disparities smaller than the line's, on rows where the road lies beyond the line), an
// untextured stretch of one surface shows nothing. `road` is the road's disparity as for
// ScoreImage. Linked components become one (the left one's label; `labels`, when given, is
// relabelled to match); options.link_max_gap = 0 returns the components unchanged.
// `allow` (optional) gets the left part, its end column and disparity, and the right part, its
// start column and disparity, and may veto the link (e.g. when the gap is too long on the
// ground); when `labels` is given, the left part's pixels there already carry its label.
using LinkVeto = std::function<bool(const HistogramComponent& a, int x0, float d0, const HistogramComponent& b,
                                    int x1, float d1)>;
std::vector<HistogramComponent> LinkComponents(std::vector<HistogramComponent> components, const cv::Mat& disparity,
                                               const cv::Mat& road, const HistogramOptions& options,
                                               cv::Mat* labels = nullptr, const LinkVeto& allow = nullptr);

// The columns [first, last] of a component to project: from its first to its last column with a
// centroid, less `trim` at each end when it is wider than 2 trim + 1. Block matching carries a
// foreground object's disparity up to half a window beyond its edges (foreground fattening), so
// the front detector trims half the block width. first > last when no column has a centroid.
std::pair<int, int> ProjectedColumns(const HistogramComponent& component, int trim);

// The columns [first, last] of a disparity image holding any valid disparity (first > last when
// none): what the view and the matcher's border let be seen. A component reaching within a
// window of them may be cut there by the view's edge rather than ended by the object.
std::pair<int, int> ValidColumns(const cv::Mat& disparity);

// The disparity of bin centre `row`.
inline double BinDisparity(const HistogramOptions& o, double row) { return o.min_disparity + (row + 0.5) * o.bin_px; }

}  // namespace dps
