// dps — area-correlation stereo on rectified pairs (Gandhi & Trivedi 2006, section V, steps 1-4).
//
// Conventions
// - Input: a rectified pair of 8-bit grey images of the same size. The left image is the
//   reference: left(x, y) matches right(x - d, y) for disparity d (Middlebury / KITTI). For motion
//   stereo the "left" image is the earlier side view (see virtual_view.h) and d may be negative.
// - Output: CV_32F disparity in pixels (sub-pixel), one per left pixel; pixels without a reliable
//   match hold kInvalidDisparity (+infinity): test with std::isfinite.
//
// Steps
// 1. Laplacian-of-Gaussian band-pass prefilter (eq. 12): Gaussian of sigma log_sigma_px, then the
//    3x3 Laplacian (in floating point), times prefilter_gain, clamped to +-prefilter_cap and
//    offset to 0..2 cap (8-bit); it removes brightness differences between the cameras and keeps
//    texture.
// 2. Sum of absolute differences over a block_width x block_height window (eq. 13) for every
//    disparity in [min_disparity, min_disparity + num_disparities), with running sums down the
//    columns and along the row, so the cost per pixel and disparity does not grow with the window;
//    OpenCV universal intrinsics over the disparities, cv::parallel_for_ over stripes of rows.
// 3. The best disparity, refined to sub-pixel by a V (equiangular) fit to its neighbours' costs; an
//    interest operator (the window's mean horizontal change of the LoG image must reach
//    texture_threshold) rejects uniform areas and horizontal edges; a uniqueness test rejects ambiguous minima; a left-right check compares with the best
//    match seen from the right image.
// 4. Two levels: the same search on half-resolution images fills pixels the full-resolution level
//    left invalid (low texture), with twice the coarse disparity; with cross_level_max_diff set it
//    also checks the others: a full-resolution disparity farther than that from twice the coarse
//    one is dropped (a match on a fine pattern that repeats, or on noise, which the coarser view
//    of the same window does not support).
// Validity: an image may come with a mask of the pixels that see the world (a view's pixels with a
// camera source, inside the camera's field). Invalid pixels take the value of the nearest valid one
// before the prefilter (no edge where the valid area ends), and no disparity comes from a window
// that touches an invalid pixel in either image, at either level: the edge of a camera's field is
// never matched.
// Temporal consistency (the paper's variance check over frames) is the separate, stateful
// TemporalConsistencyFilter below.
#pragma once

#include <limits>
#include <memory>
#include <utility>

#include <opencv2/core.hpp>

namespace dps {

// The value of pixels without a reliable disparity.
constexpr float kInvalidDisparity = std::numeric_limits<float>::infinity();

struct StereoOptions {
  int min_disparity = 0;        // smallest disparity searched, px; negative for motion stereo; |d| <= 16384
  int num_disparities = 64;     // number of disparities searched, 2..16384
  int block_width = 9;          // SAD window, px; odd, 3..31
  int block_height = 9;         // odd, 3..31
  double log_sigma_px = 1.0;    // Gaussian of the LoG prefilter, px; > 0
  double prefilter_gain = 6.0;  // LoG response scale before the clamp (grey levels), > 0
  int prefilter_cap = 31;       // clamp of the scaled LoG response, 1..63
  double texture_threshold = 1.0;  // interest operator: min mean |LoG(x+1) - LoG(x-1)| in the window, >= 0
  double uniqueness_ratio = 10.0;  // % by which the best cost must beat any non-adjacent one, 0..100
  bool left_right_check = true;    // reject pixels whose right-image match disagrees
  double left_right_max_diff = 1.0;  // px, >= 0
  bool two_levels = true;          // fill invalid pixels from a half-resolution level
  // The half-resolution level's matching windows as tall as the full level's in image rows (half
  // as many of its own rows, at least 3) instead of twice as tall: for views where the road's
  // disparity changes along the rows (a side view looking down at the road beside the car), so that
  // a window spans no more of that change than at full resolution. Its interest operator still
  // judges the usual (twice as tall) window.
  bool coarse_same_rows = false;
  // Full-resolution disparities differing from twice the coarse level's at that pixel by more
  // than this are dropped (px, full resolution; < 0: no check, the default). 4 px checks to two
  // pixels of the coarse level, its own step and its left-right tolerance. Off by default: on the
  // robustness battery it found more objects but also more kerbs and parts of long objects
  // (docs/experiments/detection-history.md).
  double cross_level_max_diff = -1.0;
  bool subpixel = true;            // equiangular (V) refinement
  // The kernel built for the baseline instruction set even where the CPU runs the AVX2 one (both
  // give the same disparities; for comparisons and benchmarks).
  bool baseline_kernel = false;

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// The matcher settings the detectors use by default: 64 disparities and an interest threshold of
// 4.5 (image noise of 2 grey levels on a uniform area stays below it).
StereoOptions DetectionStereoOptions();

// The LoG band-pass prefilter of step 1: CV_8U in, CV_8U out with values 0..2 cap (cap = 0 LoG).
cv::Mat LogPrefilter(const cv::Mat& grey, double sigma_px, double gain, int cap);

// The columns (first, last; inclusive) of a `width`-wide reference image that the matcher gives
// disparities for: those where the window of every searched disparity lies inside both images.
// The others stay invalid (their match could lie outside the other image).
std::pair<int, int> MatchedColumns(int width, const StereoOptions& options);

// Step 3's interest operator on a LoG image (CV_8U): 255 where the block_width x block_height
// window's sum of |LoG(x + 1) - LoG(x - 1)| reaches texture_threshold x area (edges replicated),
// else 0.
cv::Mat TextureMask(const cv::Mat& log, const StereoOptions& options);

// The matcher. It keeps its working buffers between calls (fresh buffers would cost as much as
// a good part of the matching), so use one matcher per thread.
class SadStereoMatcher {
 public:
  explicit SadStereoMatcher(const StereoOptions& options);  // checks the options
  ~SadStereoMatcher();
  SadStereoMatcher(const SadStereoMatcher&) = delete;
  SadStereoMatcher& operator=(const SadStereoMatcher&) = delete;

  // Disparity of `left` (reference) against `right`: CV_8U or CV_8UC3 (converted to grey), same
  // size, at least block size + num_disparities wide; optional validity masks as for Prepare.
  // Throws dps::Error for bad inputs.
  cv::Mat Compute(const cv::Mat& left, const cv::Mat& right, const cv::Mat& left_valid = cv::Mat(),
                  const cv::Mat& right_valid = cv::Mat());

  // A view prefiltered for matching (steps 1 and 3's interest operator, at each level), for a
  // view matched more than once: prepared once, matched with either view as the reference and
  // mirrored for matching right-to-left, instead of prefiltering it again for every matching.
  struct PreparedView {
    cv::Mat log[2];       // the LoG image, full and (two levels) half resolution
    cv::Mat textured[2];  // the interest operator's mask (255: textured window)
    // 255 where the matching window (and the prefilter's support under it) holds valid pixels
    // only; empty when the whole image is valid.
    cv::Mat window_valid[2];
    cv::Mat scratch[4];   // working memory, kept between calls
    // What Prepare derived from the last validity mask, reused while the same mask comes again (a
    // view's mask does not change from frame to frame): the mask itself (shared, not copied),
    // whether any pixel is invalid, and for each pixel the valid pixel whose value it takes.
    cv::Mat mask_seen, fill_map;
    bool mask_has_invalid = false;
  };
  // Prefilters a grey or BGR image into `view` (its buffers reused). `valid` (optional, CV_8U of
  // the image's size): 255 where the pixel sees the world; what it implies is derived once and reused
  // while the same mask (the same cv::Mat data) comes again, so a mask must not be changed in place
  // between calls. Const: concurrent calls on one matcher are safe.
  void Prepare(const cv::Mat& image, PreparedView* view, const cv::Mat& valid = cv::Mat()) const;
  // `view` turned left to right (the pair then matches the other way round).
  static void Mirror(const PreparedView& view, PreparedView* mirrored);
  // Disparity of the prepared `left` against the prepared `right` (the same size, both prepared by
  // a matcher with these options) for the left view's columns from first_column on, the others
  // invalid; the windows and the search still read the columns before it. Without first_column,
  // as Compute of the two images.
  cv::Mat Compute(const PreparedView& left, const PreparedView& right, int first_column = 0);

  const StereoOptions& options() const { return options_; }

 private:
  struct Workspace;
  // One level of prefiltered images, the left view's columns from first_column on.
  const cv::Mat& MatchLevel(const PreparedView& left, const PreparedView& right, int min_disparity,
                            int num_disparities, int level, int first_column);
  // Fills the fine level's invalid pixels from first_column on with twice the coarse disparity, and
  // drops its valid ones differing from that by more than cross_level_max_diff (when >= 0).
  void FillFromCoarse(const cv::Mat& coarse, int first_column, cv::Mat& fine) const;
  StereoOptions options_;
  std::unique_ptr<Workspace> ws_;
};

// The paper's temporal consistency check: a running mean and variance of each pixel's disparity
// over frames (exponential forgetting); pixels whose variance exceeds max_variance_px2 are
// suppressed. A pixel that turns invalid resets.
class TemporalConsistencyFilter {
 public:
  // forgetting in (0, 1]: weight of the newest frame; max_variance_px2 > 0.
  TemporalConsistencyFilter(double forgetting = 0.5, double max_variance_px2 = 1.0);

  // Feeds one frame's disparity (CV_32F, kInvalidDisparity for none) and returns it with the
  // temporally inconsistent pixels set to kInvalidDisparity. Sizes must not change between calls
  // (call Reset first).
  cv::Mat Apply(const cv::Mat& disparity);
  void Reset();

 private:
  double forgetting_;
  double max_variance_;
  cv::Mat mean_, var_;  // CV_32F
  cv::Mat seen_;        // CV_32F 1 where the last frame was valid, else 0
};

}  // namespace dps
