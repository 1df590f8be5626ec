// dps — the surround map picture: a top-down view of the vehicle frame with the own car (black),
// the detected obstacles (coloured by lane), range rings and a scale, and the ground each source covers
// lightly shaded (Gandhi & Trivedi 2006, section V-C, Fig. 1 and 7).
#pragma once

#include <deque>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/rig.h"
#include "dps/detect/coverage.h"
#include "dps/detect/detection.h"
#include "dps/map/occupancy_grid.h"
#include "dps/map/tracker.h"
#include "dps/util/lanes_csv.h"

namespace dps {

struct MapOptions {
  int size_px = 600;       // square picture, 16..8192
  double range_m = 30.0;   // from the centre to the border, > 0
  double ring_step_m = 5.0;  // > 0

  // Throws dps::Error naming the field, its value and the violated constraint.
  void Check() const;
};

// The road that no camera of `rig` sees, over the map (CV_8U of the map's size, 255 = no camera
// sees it): a camera sees a road point when it projects into the camera's valid pixels
// (CameraValidMask), not onto its own car (RigCamera::own_car), and the segment from the viewpoint
// to it passes through no box of the rig's vehicle footprint up to own_car_height_m (for a camera
// outside that box). That is the own car's shadow on the road around it, and what lies beyond
// the cameras' fields. own_car_height_m >= 0.
cv::Mat RoadNoCameraSees(const Rig& rig, double own_car_height_m, const MapOptions& options);

// What a frame's map is drawn over: each sector of `coverage` shaded (the front pair, the left and the
// right camera each in its own colour), `unseen` (RoadNoCameraSees; empty = none) cross-hatched in
// grey, hatched in magenta outside both where the frame's motion stereo tells no depth
// (Coverage::MotionBlind: the wedges about the motion's epipoles), range rings, the own car, the scale bar
// and a legend of the colours (bottom right; none on maps under about 400 px).
cv::Mat DrawMapBackground(const Vehicle& vehicle, const Coverage& coverage, const MapOptions& options,
                          const cv::Mat& unseen = cv::Mat());

// The backgrounds of the frames' coverages (DrawMapBackground): a frame's sectors are what it
// measured, so they change when a side view is not matched (standing, driving slowly), shrinks at
// speed or turns with the car, and its motion's blind wedges with the speed. Each distinct
// coverage (sectors to a tenth of a degree and a centimetre, the motion's directions to a degree
// and its discs' diameters to 5 %) is drawn once and kept, the oldest dropped beyond `capacity`
// pictures. `unseen`: as DrawMapBackground's, the same for every frame.
class MapBackgrounds {
 public:
  MapBackgrounds(const Vehicle& vehicle, const MapOptions& options, size_t capacity = 16,
                 const cv::Mat& unseen = cv::Mat());
  // The background for a frame's coverage; valid until the next call.
  const cv::Mat& For(const Coverage& coverage);

 private:
  Vehicle vehicle_;
  MapOptions options_;
  size_t capacity_;
  cv::Mat unseen_;
  std::map<std::string, cv::Mat> pictures_;
  std::deque<std::string> order_;
};

// The own car (black) on a map picture; DrawMapBackground draws it too, this redraws it over
// layers drawn later (the occupancy grid).
void DrawOwnCar(cv::Mat& map, const Vehicle& vehicle, const MapOptions& options);

// The map for one frame over a background from DrawMapBackground (same options). Obstacles are
// drawn as their ground points joined in order and thickened by a closing in the picture (the
// paper's morphological smoothing, erring towards the car), coloured by their lane
// (Detection::lane): red in the ego lane, orange in a lane to the left, purple to the right,
// grey-brown when unknown.
cv::Mat DrawSurroundMap(const cv::Mat& background, const std::vector<Detection>& detections,
                        const MapOptions& options, const std::string& caption);

// Draws lane boundaries (lane_detection.h) onto a map picture as straight lines over the map's
// range, solid or dashed as they are; the ego lane's (left, right) thicker than its neighbours'.
void DrawLanes(cv::Mat& map, const std::vector<LaneBoundaryRow>& lanes, const MapOptions& options);

// Writes the ego's lateral position in its lane, the lane's width and the heading relative to it
// under the map's caption.
void DrawEgoLane(cv::Mat& map, const EgoLaneRow& ego);

// Draws the confirmed tracks onto a map picture: id, class and lane (e.g. "7 vehicle L-1"), an
// arrow to the position predicted ahead and the 1-sigma ellipse of that prediction.
void DrawTracks(cv::Mat& map, const std::vector<TrackState>& tracks, const MapOptions& options);

// One frame's whole map as dps-process writes it: the background, the occupancy grid under the own
// car, the detections, the tracks and the caption.
cv::Mat DrawFrameMap(const cv::Mat& background, const OccupancyGrid& grid, const Vehicle& vehicle,
                     const std::vector<Detection>& detections, const std::vector<TrackState>& tracks,
                     const MapOptions& options, const std::string& caption);
// The same into `map`, whose buffer is reused when it already has the background's size and type:
// for a picture every frame (a fresh 600x600 picture each time cost dps-bench's picture step
// 0.1-0.2 ms more, the pages of a new megabyte faulting in).
void DrawFrameMap(const cv::Mat& background, const OccupancyGrid& grid, const Vehicle& vehicle,
                  const std::vector<Detection>& detections, const std::vector<TrackState>& tracks,
                  const MapOptions& options, const std::string& caption, cv::Mat& map);

// The paper's six-panel diagnostics of one source (Fig. 7, 9-10), each panel the size of the
// views: the two matched views, their composite (left in red, right in cyan), the colour-coded
// disparity, the column histogram (disparity up, columns across) and the obstacle image. For the
// front the obstacle image is the histogram-shaped image of centroid disparities; for a side, the
// bottom-most pixels in the view. Empty results give a grey panel set with the title.
cv::Mat DrawDiagnostics(const std::string& title, const cv::Mat& reference_view, const cv::Mat& other_view,
                        const cv::Mat& disparity, const cv::Mat& histogram, const cv::Mat& obstacle,
                        double min_disparity, double max_disparity, cv::Size panel);

}  // namespace dps
