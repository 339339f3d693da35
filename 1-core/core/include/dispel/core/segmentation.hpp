#pragma once
/// @file
/// Single-pass segmentation of a 2D laser scan into objects (thesis section 3.2.1, the "modified
/// DBSCAN"): beams are already ordered by bearing, so one pass that compares each beam with the
/// previous valid one finds the clusters in O(n).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "dispel/core/laser_scan.hpp"

namespace dispel {

/// How the gap between two bearing-neighbouring beams is measured.
enum class GapMetric {
  /// Exact Euclidean distance between the two points: the law of cosines,
  /// d^2 = r1^2 + r2^2 - 2 r1 r2 cos(dtheta), with dtheta the true angle between the beams.
  kEuclidean,
  /// The thesis's approximation d ~ |r1 - r2|. It ignores the angle between the beams, so it
  /// under-estimates the gap whenever the beams are far apart sideways: at long range
  /// (the sideways spacing is about r * dtheta, 0.12 m at 40 m with 0.17 deg), with coarse
  /// scanners (1 deg at 6 m is already 0.1 m), across runs of invalid beams, and on surfaces seen
  /// square-on, where neighbouring ranges are almost equal however far apart the points are.
  /// It over-joins there: a sparse row of points becomes one object.
  kRangeDifference,
};

/// A sector of bearings in the sensor frame, from begin_rad counter-clockwise to end_rad.
/// Beams whose bearing lies in it (ends included) are masked: never part of an object.
struct AngleSector {
  double begin_rad = 0.0;
  double end_rad = 0.0;
};

/// True when @p bearing_rad (any turn) lies in @p sector, ends included.
bool sector_contains(const AngleSector& sector, double bearing_rad);

/// Parameters of the segmentation. eps and N_min are the thesis's (Appendix A); the gap is measured
/// exactly (the thesis's |r1 - r2| is thesis_config()'s).
struct SegmentationConfig {
  /// eps: the largest gap between consecutive points of one object, metres.
  double cluster_gap_m = 0.1;
  /// Far from the scanner, neighbouring beams land farther apart than eps on a surface seen at a
  /// slant (0.35-degree beams are 6 cm apart square-on at 10 m, 18 cm at 70 degrees from it), and
  /// such a surface would break into pieces under N_min. Two consecutive points also join when
  /// they are within this many beam spacings (the nearer point's range times the angle increment)
  /// of each other: 3 keeps a surface seen up to 70 degrees from square-on whole. Only with the
  /// Euclidean gap; beyond eps / (spacings x increment), 5 m at 0.35 degrees. 0: eps at every
  /// range (the thesis).
  double cluster_gap_spacings = 3.0;
  /// N_min: objects with fewer points are noise.
  int min_points = 8;
  /// An object this wide, metres, is never noise for its beam count alone: where it covers fewer
  /// than min_points beams (farther than min_width_m / (min_points x angle increment), 4 m for
  /// 0.1 m at 0.35 degrees and N_min 4), N_min falls to the beams it covers at the object's range,
  /// rounded, never below 2 (a single beam stays noise), for an object that stands out whole in
  /// front of what is beside it (both neighbouring beams farther or without a return) and lies
  /// within 0.8 of the scanner's range_max (near the end of its reach returns come and go). A leg
  /// at 6 m is 3 beams of a 0.35-degree scanner. 0 (the default and the thesis): N_min is
  /// min_points at every range. docs/dynamic_filter.md says what 0.1 gains and costs.
  double min_width_m = 0.0;
  /// How the gap between neighbouring beams is measured.
  GapMetric gap_metric = GapMetric::kEuclidean;
  /// Merge clusters whose facing edge points (last of one, first of a later one in bearing order)
  /// are within cluster_gap_m in Euclidean distance, e.g. the two legs of one person seen with the
  /// wall between them. Merging never crosses a masked sector.
  bool merge_facing_edges = true;
  /// On scans that cover a full circle, treat the last and first beams as neighbours, so an
  /// object across the seam is one object.
  bool join_full_circle_seam = true;
  /// Sectors to ignore, e.g. where mirrors fold the view to the floor. They break adjacency.
  std::vector<AngleSector> masked_sectors;

  /// Throws std::invalid_argument naming the first bad field and its value.
  void validate() const;
};

/// Per-beam labels that are not an object index.
inline constexpr std::int32_t kLabelNoise = -1;    ///< Valid beam in a cluster below min_points.
inline constexpr std::int32_t kLabelInvalid = -2;  ///< NaN, infinite or out-of-limits range.
inline constexpr std::int32_t kLabelMasked = -3;   ///< Beam inside a masked sector.

/// What lies just beyond an object's edge beam, in bearing order. Tracking uses it to decide
/// whether an edge is the object's true outline or may be cut off.
enum class EdgeNeighbour : std::uint8_t {
  kFieldOfViewEnd,  ///< The edge beam is the first or last beam of a scan that is not a circle.
  kMaskedSector,    ///< The next beam is masked.
  kInvalid,         ///< The next beam has no valid return.
  kCloser,          ///< The next beam is nearer: the edge may be occluded.
  kFarther,         ///< The next beam is farther: the edge is the object's outline.
};

/// One object found in a scan. Points are in the sensor frame, metres.
struct ScanObject {
  /// First and last beam in counter-clockwise bearing order. On a full-circle scan an object
  /// across the seam has first_beam > last_beam: its beams are first..n-1 then 0..last.
  /// Beams between them may belong to something else (a merged pair of legs has the wall between
  /// them); beam_labels says which beams are this object's.
  std::int32_t first_beam = 0;
  std::int32_t last_beam = 0;
  std::int32_t point_count = 0;    ///< Beams labelled with this object.
  std::int32_t cluster_count = 0;  ///< Clusters merged into it by facing edges (1 = none).
  Eigen::Vector2d first_point_m = Eigen::Vector2d::Zero();      ///< Point of first_beam.
  Eigen::Vector2d last_point_m = Eigen::Vector2d::Zero();       ///< Point of last_beam.
  Eigen::Vector2d centroid_m = Eigen::Vector2d::Zero();         ///< Mean of the object's points.
  EdgeNeighbour before_first = EdgeNeighbour::kFieldOfViewEnd;  ///< Beyond first_beam.
  EdgeNeighbour after_last = EdgeNeighbour::kFieldOfViewEnd;    ///< Beyond last_beam.

  bool straddles_seam() const { return first_beam > last_beam; }
};

/// The result of segmenting one scan.
struct Segmentation {
  /// kNone, or why the scan was rejected (then everything below is empty or zero).
  ScanIssue issue = ScanIssue::kNone;
  /// One label per beam: the index into objects, or kLabelNoise / kLabelInvalid / kLabelMasked.
  std::vector<std::int32_t> beam_labels;
  /// Objects ordered by first_beam.
  std::vector<ScanObject> objects;
  /// True when the scan covers a full circle and its seam was joined.
  bool full_circle = false;
  std::int32_t valid_beams = 0;    ///< Beams with a usable range outside masked sectors.
  std::int32_t invalid_beams = 0;  ///< Beams labelled kLabelInvalid.
  std::int32_t masked_beams = 0;   ///< Beams labelled kLabelMasked.
  std::int32_t noise_beams = 0;    ///< Beams labelled kLabelNoise.
  std::int32_t clusters = 0;       ///< Clusters found by the pass, before merging and N_min.
  std::int32_t merges = 0;         ///< Facing-edge merges performed.
};

namespace segmentation_detail {
// A run of bearing-consecutive beams joined by the pass. Positions count beams in processing
// order, which starts at a cluster boundary on full-circle scans.
struct Cluster {
  std::int32_t first_pos, last_pos;
  std::int32_t first_beam, last_beam;
  std::int32_t count;
  std::int32_t run;  // Clusters with different runs have a masked sector between them.
  float first_x, first_y, last_x, last_y, last_range;
  double sum_x, sum_y;
};
// An object being assembled from clusters by the facing-edge merge.
struct Object {
  std::int32_t first_cluster, last_cluster;
  std::int32_t count, cluster_count;
  std::int32_t reach_pos;  // Clusters starting after this position cannot merge into it.
  double sum_x, sum_y;
  bool alive;
};
}  // namespace segmentation_detail

/// Segments scans. Keeps buffers and a table of beam directions between calls, so that
/// segmenting a stream of scans of one geometry allocates nothing after the first scan.
/// Not thread-safe: use one Segmenter per thread.
class Segmenter {
 public:
  /// @throws std::invalid_argument if config.validate() does.
  explicit Segmenter(SegmentationConfig config);

  /// Segments @p scan into @p out (reusing its storage). A scan that fails check_scan() is
  /// rejected: out.issue says why and out holds no labels or objects.
  void segment(const LaserScan& scan, Segmentation& out);
  /// The same; with min_width_m, an object below min_points is one only where @p seen_before says
  /// something was at its centroid (sensor frame, metres) in the scan before: a far leg is there
  /// scan after scan, a sporadic return outdoors is not.
  using SeenBefore = std::function<bool(const Eigen::Vector2d&)>;
  void segment(const LaserScan& scan, Segmentation& out, const SeenBefore& seen_before);

  /// Convenience overload returning a fresh result.
  Segmentation segment(const LaserScan& scan) {
    Segmentation out;
    segment(scan, out);
    return out;
  }

  const SegmentationConfig& config() const { return config_; }

 private:
  void update_geometry(const LaserScan& scan);
  // (cluster_gap_spacings x the scan's angle increment)^2.
  float spacing_sq(const LaserScan& scan) const;
  std::int32_t find_rotation_start(const LaserScan& scan, bool& seam_continuous) const;
  void merge_clusters(bool seam_continuous, std::int32_t final_run, std::int32_t n,
                      double increment_rad);
  void write_objects(const LaserScan& scan, Segmentation& out, const SeenBefore& seen_before);
  /// N_min for @p obj: min_points, lowered with range by min_width_m (where @p seen_before, when
  /// given, says yes).
  std::int32_t min_points_of(const LaserScan& scan, const segmentation_detail::Object& obj,
                             const SeenBefore& seen_before) const;
  EdgeNeighbour neighbour_of(const LaserScan& scan, std::int32_t beam, int step) const;

  SegmentationConfig config_;
  double cluster_gap_sq_m2_;

  // Geometry cache: recomputed only when the scan's angles or size change.
  double cached_angle_min_rad_ = 0.0;
  double cached_increment_rad_ = 0.0;
  std::size_t cached_size_ = 0;
  bool full_circle_ = false;
  bool any_masked_ = false;
  std::vector<float> unit_x_;
  std::vector<float> unit_y_;
  std::vector<std::uint8_t> masked_;

  // Scratch reused between scans.
  std::vector<segmentation_detail::Cluster> clusters_;
  std::vector<segmentation_detail::Object> work_objects_;
  std::vector<std::int32_t> object_of_cluster_;
  std::vector<std::int32_t> cluster_label_;
  std::vector<std::int32_t> open_;
  std::vector<std::int32_t> order_;
};

}  // namespace dispel
