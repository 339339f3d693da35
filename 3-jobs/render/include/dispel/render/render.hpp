#pragma once
/// @file
/// `dispel render` and `dispel eval --plot`: pictures of what the filter did, drawn with Cairo
/// into PNG or SVG files. See docs/rendering.md.
///
/// Two views of a ROS 1 bag:
///  - map: every scan's points accumulated in a fixed frame (odometry and the laser mount, the
///    simulator's ground truth, or the identity for a static sensor), kept points dark, removed
///    points coloured by their label (<scan-topic>_labels of a filtered bag), the robot's
///    trajectory, a scale bar, a legend and a title. The points are streamed into a fixed-size
///    raster of counts per pixel and class: memory does not grow with the recording's length.
///  - scan: one scan in the sensor frame, its points coloured by the object dispel's segmentation
///    puts them in, masked sectors shaded, and the filter's tracks (run over the scans up to it)
///    with their velocity arrows and ids.

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dispel/core/classification.hpp"
#include "dispel/eval/beam_evaluation.hpp"

namespace dispel::render {

/// An opaque colour, 8 bits per channel.
struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
  bool operator!=(const Rgb& o) const { return !(*this == o); }
};

/// The colours of the pictures (docs/rendering.md, "Colours").
namespace colours {
inline constexpr Rgb kBackground{255, 255, 255};
/// Kept points (labels 0, 3, 4 and 7, or every point of an unfiltered bag) are grey: kKeptFaint
/// where a pixel was hit once, darkening to kKept where it was hit kKeptSaturation times or more.
inline constexpr Rgb kKept{20, 20, 20};
inline constexpr Rgb kKeptFaint{150, 150, 150};
inline constexpr int kKeptSaturation = 10;
inline constexpr Rgb kDynamic{215, 38, 38};         ///< Removed, label 1.
inline constexpr Rgb kUnknown{245, 145, 0};         ///< Removed, label 2 (presumption of guilt).
inline constexpr Rgb kMovedLater{140, 60, 200};     ///< Removed by dispel clean, label 5.
inline constexpr Rgb kVacated{0, 160, 170};         ///< Removed by dispel clean, label 6.
inline constexpr Rgb kWalkedLeg{225, 80, 160};      ///< Removed by dispel clean, label 8.
inline constexpr Rgb kTrajectory{33, 102, 172};     ///< The robot's path.
inline constexpr Rgb kNoise{165, 165, 165};         ///< Scan view: a valid beam in no object.
inline constexpr Rgb kMaskedSector{222, 222, 235};  ///< Scan view: masked sectors' shade.
inline constexpr Rgb kStaticTrack{60, 60, 60};      ///< Scan view: a static track's marker.
}  // namespace colours

/// Scan view: the colour of object @p object_index of the segmentation (a palette that cycles;
/// it holds neither red nor orange, which mean dynamic and unknown).
Rgb object_colour(std::size_t object_index);

/// The colour of a track's marker and arrow by its class.
Rgb track_colour(ObjectClass object_class);

/// Maps metres in the drawn frame (x right, y up) to image pixels (u right, v down); the pixel
/// holding a point is (floor(u), floor(v)).
struct PixelTransform {
  double scale_px_per_m = 1.0;
  double centre_x_m = 0.0, centre_y_m = 0.0;    ///< The point drawn at (centre_u, centre_v).
  double centre_u_px = 0.0, centre_v_px = 0.0;  ///< Pixel coordinates of the plot's centre.

  Eigen::Vector2d to_pixel(const Eigen::Vector2d& p_m) const {
    return {centre_u_px + (p_m.x() - centre_x_m) * scale_px_per_m,
            centre_v_px - (p_m.y() - centre_y_m) * scale_px_per_m};
  }
};

struct RenderOptions {
  std::string input;           ///< A ROS 1 bag, filtered by `dispel filter` or not.
  std::string output;          ///< .png or .svg; written atomically.
  std::string view = "map";    ///< "map" or "scan".
  std::string frame = "odom";  ///< "odom" (odometry + mount) or "truth" (ground truth + mount).
  std::string scan_topic = "/scan";
  std::string odom_topic = "/odom";
  std::string truth_topic = "/ground_truth";
  bool static_sensor = false;    ///< The sensor does not move: identity pose, no odometry needed.
  std::optional<double> from_s;  ///< Map view: first scan drawn, seconds from the bag's start.
  std::optional<double> to_s;    ///< Map view: last scan drawn, seconds from the bag's start.
  std::int64_t scan_index = 0;   ///< Scan view: 0-based among the scan topic's messages.
  std::optional<std::string> config_path;  ///< Scan view: YAML; DynamicFilterConfig{} without it.
  bool scale_to_scanner = false;           ///< Scan view: as `dispel filter --scale-to-scanner`.
  int width_px = 1600;
  int height_px = 1200;
  /// How far beyond the first or last pose a scan's pose may be taken from it.
  double pose_tolerance_s = 0.05;
};

/// A track drawn in the scan view.
struct DrawnTrack {
  std::uint64_t id = 0;
  ObjectClass object_class = ObjectClass::kStatic;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();    ///< Sensor frame.
  Eigen::Vector2d velocity_mps = Eigen::Vector2d::Zero();  ///< Sensor frame.
  bool seen = false;                                       ///< Matched to an object of this scan.
};

/// What was drawn.
struct RenderResult {
  int width_px = 0;
  int height_px = 0;
  /// Map view: the fixed frame to the image; scan view: the sensor frame to the image.
  PixelTransform transform;
  /// Radius of a track's ring in the scan view, pixels (the ring's line is centred on it).
  double track_ring_radius_px = 0.0;
  bool labelled = false;  ///< The bag has <scan-topic>_labels: points coloured by label.
  std::int64_t scans_drawn = 0;
  std::int64_t scans_without_pose = 0;  ///< Map view: in the window but skipped (no pose).
  std::int64_t points_kept = 0;
  std::int64_t points_dynamic = 0;
  std::int64_t points_unknown = 0;
  std::int64_t points_moved_later = 0;  ///< `dispel clean`'s label 5.
  std::int64_t points_vacated = 0;      ///< `dispel clean`'s label 6.
  std::int64_t points_walked_legs = 0;  ///< `dispel clean`'s label 8.
  /// Points removed by `dispel clean` beyond the online filter's labels (5, 6 and 8).
  std::int64_t points_removed_offline() const {
    return points_moved_later + points_vacated + points_walked_legs;
  }
  double from_s = 0.0, to_s = 0.0;  ///< The window drawn, seconds from the bag's start.
  std::int64_t objects = 0;         ///< Scan view: objects in the segmentation.
  std::vector<DrawnTrack> tracks;   ///< Scan view.
};

/// Renders the bag. The output appears only when complete. @throws jobs::JobError
/// with a one-line message naming the problem, JobCancelled when @p cancel became true.
RenderResult render_bag(const RenderOptions& options, const std::atomic<bool>* cancel = nullptr);

/// Where the bars of an evaluation plot were drawn (pixels), in the order preservation,
/// rejection, still-actor removal; a rate that is not defined has an empty bar.
struct PlotLayout {
  struct Bar {
    double x = 0.0, y = 0.0, width = 0.0, height = 0.0;
  };
  std::vector<Bar> bars;
  double zero_v_px = 0.0;  ///< Image row of rate 0.
  double one_v_px = 0.0;   ///< Image row of rate 1.
};

inline constexpr Rgb kPlotBar{33, 102, 172};      ///< Rate bars.
inline constexpr Rgb kPlotHistogram{90, 90, 90};  ///< Latency histogram bars.

/// `dispel eval --plot`: the detection-latency histogram (with median and p90) and the per-class
/// rates (preservation, rejection, still-actor removal) as bars, into a .png or .svg written
/// atomically. @p title heads the picture. @throws jobs::JobError
PlotLayout plot_evaluation(const eval::Rates& rates, const std::string& title,
                           const std::string& output, int width_px = 1600, int height_px = 900);

/// "1600x1200" -> (1600, 1200); @throws jobs::JobError unless both are integers in [200, 10000].
std::pair<int, int> parse_image_size(const std::string& text);

}  // namespace dispel::render
