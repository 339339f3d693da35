#include "dispel/core/segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "dispel/core/pose2.hpp"

namespace dispel {
namespace {

[[noreturn]] void reject(const std::string& message) { throw std::invalid_argument(message); }

template <typename T>
std::string str(const T& value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

inline float square(float v) { return v * v; }

using segmentation_detail::Cluster;
using segmentation_detail::Object;

// What the pass reads.
struct PassInput {
  const float* ranges;
  const float* unit_x;
  const float* unit_y;
  const std::uint8_t* masked;
  float range_min, range_max, gap, gap_sq;
  float spacing_sq;  // (cluster_gap_spacings x angle increment)^2, see within_gap().
};

// Whether two points @p dist_sq apart (squared, metres) are of one cluster: within eps, or within
// cluster_gap_spacings beam spacings at the nearer point's range @p nearer_m (@p spacing_sq is that
// count times the angle increment, squared). Far away a surface seen at a slant has its points
// farther apart than eps.
inline bool within_gap(float dist_sq, float nearer_m, float gap_sq, float spacing_sq) {
  return dist_sq <= std::max(gap_sq, spacing_sq * nearer_m * nearer_m);
}

// What the pass carries from one index range to the next (the two halves of a rotated circle).
struct PassState {
  bool have_prev = false;
  float prev_x = 0.0F, prev_y = 0.0F, prev_range = 0.0F;
  std::int32_t prev_beam = 0, prev_pos = 0;
  std::int32_t run = 0, invalid = 0, masked = 0;
  // The open cluster's running sums, flushed into the cluster when it closes.
  std::int32_t open_count = 0;
  double open_sum_x = 0.0, open_sum_y = 0.0;
};

void close_cluster(PassState& st, std::vector<Cluster>& clusters) {
  if (st.open_count == 0) return;
  Cluster& c = clusters.back();
  c.last_pos = st.prev_pos;
  c.last_beam = st.prev_beam;
  c.count = st.open_count;
  c.sum_x = st.open_sum_x;
  c.sum_y = st.open_sum_y;
  c.last_x = st.prev_x;
  c.last_y = st.prev_y;
  c.last_range = st.prev_range;
  st.open_count = 0;
  st.open_sum_x = st.open_sum_y = 0.0;
}

// The pass over beams [begin, end) (thesis Algorithm 1): a valid beam joins the open cluster when
// its gap to the previous valid beam is at most eps; otherwise it opens a new cluster. Invalid
// beams are skipped, so the gap is measured across them (with the true angle under the Euclidean
// metric); masked beams close the open cluster. The state is a local copy so that the compiler
// can keep it in registers (the label stores could otherwise alias it).
template <bool kEuclidean, bool kAnyMasked>
PassState run_pass(const PassInput& in, std::int32_t begin, std::int32_t end,
                   std::int32_t pos_offset, PassState st, std::int32_t* labels,
                   std::vector<Cluster>& clusters) {
  auto cluster_id = static_cast<std::int32_t>(clusters.size()) - 1;
  const float* const ranges = in.ranges;  // Locals: push_back below would force reloads.
  const float* const unit_x = in.unit_x;
  const float* const unit_y = in.unit_y;
  const std::uint8_t* const masked = in.masked;
  const float range_min = in.range_min;
  const float range_max = in.range_max;
  const float gap = in.gap;
  const float gap_sq = in.gap_sq;
  for (std::int32_t i = begin; i < end; ++i) {
    if (kAnyMasked && masked[i] != 0) {
      labels[i] = kLabelMasked;
      ++st.masked;
      st.have_prev = false;
      ++st.run;
      continue;
    }
    const float r = ranges[i];
    if (!(r >= range_min && r <= range_max)) {
      labels[i] = kLabelInvalid;
      ++st.invalid;
      continue;
    }
    const float x = r * unit_x[i];
    const float y = r * unit_y[i];
    bool join = st.have_prev;
    if (kEuclidean) {
      const float dx = x - st.prev_x;
      const float dy = y - st.prev_y;
      join =
          join && within_gap(dx * dx + dy * dy, std::min(r, st.prev_range), gap_sq, in.spacing_sq);
    } else {
      join = join && std::fabs(r - st.prev_range) <= gap;
    }
    if (!join) {
      close_cluster(st, clusters);
      Cluster c{};
      c.first_pos = i + pos_offset;
      c.first_beam = i;
      c.run = st.run;
      c.first_x = x;
      c.first_y = y;
      clusters.push_back(c);
      ++cluster_id;
    }
    ++st.open_count;
    st.open_sum_x += x;
    st.open_sum_y += y;
    labels[i] = cluster_id;
    st.prev_x = x;
    st.prev_y = y;
    st.prev_range = r;
    st.prev_beam = i;
    st.prev_pos = i + pos_offset;
    st.have_prev = true;
  }
  return st;
}

}  // namespace

bool sector_contains(const AngleSector& sector, double bearing_rad) {
  constexpr double kTwoPi = 2.0 * kPi;
  double offset = std::fmod(bearing_rad - sector.begin_rad, kTwoPi);  // Counter-clockwise.
  if (offset < 0.0) offset += kTwoPi;
  return offset <= sector.end_rad - sector.begin_rad;
}

void SegmentationConfig::validate() const {
  if (!std::isfinite(cluster_gap_m) || !(cluster_gap_m > 0.0)) {
    reject("segmentation.cluster_gap_m must be a finite number > 0, got " + str(cluster_gap_m));
  }
  if (!std::isfinite(cluster_gap_spacings) || cluster_gap_spacings < 0.0 ||
      cluster_gap_spacings > 20.0) {
    reject("segmentation.cluster_gap_spacings must be a number in [0, 20], got " +
           str(cluster_gap_spacings));
  }
  if (min_points < 1) {
    reject("segmentation.min_points must be >= 1, got " + str(min_points));
  }
  if (!std::isfinite(min_width_m) || min_width_m < 0.0) {
    reject("segmentation.min_width_m must be a finite number >= 0, got " + str(min_width_m));
  }
  if (gap_metric != GapMetric::kEuclidean && gap_metric != GapMetric::kRangeDifference) {
    reject("segmentation.gap_metric has an unknown value " + str(static_cast<int>(gap_metric)));
  }
  for (std::size_t i = 0; i < masked_sectors.size(); ++i) {
    const AngleSector& s = masked_sectors[i];
    const std::string name = "segmentation.masked_sectors[" + str(i) + "]";
    if (!std::isfinite(s.begin_rad) || !std::isfinite(s.end_rad)) {
      reject(name + " must have finite begin_rad and end_rad, got " + str(s.begin_rad) + " and " +
             str(s.end_rad));
    }
    const double width = s.end_rad - s.begin_rad;
    if (!(width > 0.0) || width >= 2.0 * kPi) {
      reject(name + " must satisfy begin_rad < end_rad < begin_rad + 2 pi, got begin_rad " +
             str(s.begin_rad) + " and end_rad " + str(s.end_rad));
    }
  }
}

Segmenter::Segmenter(SegmentationConfig config) : config_(std::move(config)) {
  config_.validate();
  cluster_gap_sq_m2_ = config_.cluster_gap_m * config_.cluster_gap_m;
}

void Segmenter::update_geometry(const LaserScan& scan) {
  const std::size_t n = scan.size();
  if (n == cached_size_ && scan.angle_min_rad == cached_angle_min_rad_ &&
      scan.angle_increment_rad == cached_increment_rad_) {
    return;
  }
  cached_size_ = n;
  cached_angle_min_rad_ = scan.angle_min_rad;
  cached_increment_rad_ = scan.angle_increment_rad;
  unit_x_.resize(n);
  unit_y_.resize(n);
  masked_.assign(n, 0);
  any_masked_ = false;
  for (std::size_t i = 0; i < n; ++i) {
    const double bearing = scan.bearing_rad(i);
    unit_x_[i] = static_cast<float>(std::cos(bearing));
    unit_y_[i] = static_cast<float>(std::sin(bearing));
    for (const AngleSector& s : config_.masked_sectors) {
      if (sector_contains(s, bearing)) {
        masked_[i] = 1;
        any_masked_ = true;
      }
    }
  }
  // A scan whose beams span a whole turn (some drivers repeat the first bearing at the end).
  const double span = static_cast<double>(n) * scan.angle_increment_rad;
  full_circle_ =
      config_.join_full_circle_seam && n > 1 && span >= 2.0 * kPi - 0.5 * scan.angle_increment_rad;
}

// On a full-circle scan the pass must start where a cluster starts, or the cluster across the seam
// would be cut in two. Returns the first valid beam that does not join its predecessor (going
// round the seam); seam_continuous tells whether no masked beam lies between the two.
std::int32_t Segmenter::find_rotation_start(const LaserScan& scan, bool& seam_continuous) const {
  const auto n = static_cast<std::int32_t>(scan.size());
  const bool euclid = config_.gap_metric == GapMetric::kEuclidean;
  const float gap = static_cast<float>(config_.cluster_gap_m);
  const auto gap_sq = static_cast<float>(cluster_gap_sq_m2_);
  const float spacing = spacing_sq(scan);
  auto usable = [&](std::int32_t i) { return masked_[i] == 0 && scan.is_valid(i); };
  auto joins = [&](std::int32_t a, std::int32_t b) {
    const float ra = scan.ranges_m[a];
    const float rb = scan.ranges_m[b];
    if (!euclid) return std::fabs(ra - rb) <= gap;
    return within_gap(
        square(ra * unit_x_[a] - rb * unit_x_[b]) + square(ra * unit_y_[a] - rb * unit_y_[b]),
        std::min(ra, rb), gap_sq, spacing);
  };
  seam_continuous = false;
  std::int32_t last = n - 1;
  bool broken = false;
  while (last >= 0 && !usable(last)) {
    broken = broken || masked_[last] != 0;
    --last;
  }
  if (last < 0) return 0;  // Nothing valid: any start will do.
  std::int32_t prev = last;
  for (std::int32_t i = 0; i <= last; ++i) {
    if (masked_[i] != 0) {
      broken = true;
      continue;
    }
    if (!scan.is_valid(i)) continue;
    if (broken || !joins(prev, i)) {
      seam_continuous = !broken;
      return i;
    }
    prev = i;
  }
  return 0;  // Every valid beam joins its predecessor: one ring; start anywhere.
}

float Segmenter::spacing_sq(const LaserScan& scan) const {
  const double per_m = config_.cluster_gap_spacings * std::fabs(scan.angle_increment_rad);
  return static_cast<float>(per_m * per_m);
}

void Segmenter::segment(const LaserScan& scan, Segmentation& out) { segment(scan, out, {}); }

void Segmenter::segment(const LaserScan& scan, Segmentation& out, const SeenBefore& seen_before) {
  out.issue = check_scan(scan);
  out.beam_labels.clear();
  out.objects.clear();
  out.full_circle = false;
  out.valid_beams = out.invalid_beams = out.masked_beams = out.noise_beams = 0;
  out.clusters = out.merges = 0;
  if (out.issue != ScanIssue::kNone) return;

  update_geometry(scan);
  const auto n = static_cast<std::int32_t>(scan.size());
  out.beam_labels.resize(n);
  out.full_circle = full_circle_;

  bool seam_continuous = false;
  const std::int32_t start = full_circle_ ? find_rotation_start(scan, seam_continuous) : 0;

  clusters_.clear();
  const PassInput in{scan.ranges_m.data(),
                     unit_x_.data(),
                     unit_y_.data(),
                     masked_.data(),
                     scan.range_min_m,
                     scan.range_max_m,
                     static_cast<float>(config_.cluster_gap_m),
                     static_cast<float>(cluster_gap_sq_m2_),
                     spacing_sq(scan)};
  auto pass = config_.gap_metric == GapMetric::kEuclidean
                  ? (any_masked_ ? &run_pass<true, true> : &run_pass<true, false>)
                  : (any_masked_ ? &run_pass<false, true> : &run_pass<false, false>);
  std::int32_t* labels = out.beam_labels.data();
  PassState st = pass(in, start, n, -start, PassState{}, labels, clusters_);
  st = pass(in, 0, start, n - start, st, labels, clusters_);
  close_cluster(st, clusters_);

  out.invalid_beams = st.invalid;
  out.masked_beams = st.masked;
  out.valid_beams = n - st.invalid - st.masked;
  out.clusters = static_cast<std::int32_t>(clusters_.size());

  merge_clusters(seam_continuous, st.run, n, scan.angle_increment_rad);
  write_objects(scan, out, seen_before);
}

// Facing-edge merge. Clusters are visited in processing order; each is appended to the open object
// whose last edge point is nearest to its first edge point within eps, or starts a new object.
// An object stays open while a later cluster could still be within eps of its last edge (see
// reach_of): a few beams at long range, so the merge stays linear in the number of clusters.
void Segmenter::merge_clusters(bool seam_continuous, std::int32_t final_run, std::int32_t n,
                               double increment_rad) {
  const auto cluster_count = static_cast<std::int32_t>(clusters_.size());
  work_objects_.clear();
  object_of_cluster_.resize(cluster_count);
  open_.clear();
  const double gap = config_.cluster_gap_m;

  // Last position from which a later cluster could still be within eps of cluster c's last edge.
  // A point dtheta further on is at least r * sin(dtheta) >= r * dtheta * 2 / pi away (up to
  // 90 deg, and r beyond), so nothing past dtheta = (pi / 2) * eps / r can be reached.
  const double beams_per_rad = 1.0 / increment_rad;
  auto reach_of = [&](std::int32_t c) {
    const Cluster& cl = clusters_[c];
    if (cl.last_range <= gap) return cl.last_pos + n;
    const double window = 0.5 * kPi * gap / cl.last_range * beams_per_rad;
    return cl.last_pos + static_cast<std::int32_t>(window) + 1;
  };
  auto new_object = [&](std::int32_t c) {
    const Cluster& cl = clusters_[c];
    work_objects_.push_back({c, c, cl.count, 1, reach_of(c), cl.sum_x, cl.sum_y, true});
    object_of_cluster_[c] = static_cast<std::int32_t>(work_objects_.size()) - 1;
    return object_of_cluster_[c];
  };
  auto gap_sq_between = [&](const Cluster& last_of, const Cluster& first_of) {
    const double dx = static_cast<double>(last_of.last_x) - first_of.first_x;
    const double dy = static_cast<double>(last_of.last_y) - first_of.first_y;
    return dx * dx + dy * dy;
  };

  if (!config_.merge_facing_edges) {
    for (std::int32_t c = 0; c < cluster_count; ++c) new_object(c);
    return;
  }

  for (std::int32_t c = 0; c < cluster_count; ++c) {
    const Cluster& cl = clusters_[c];
    std::int32_t best = -1;
    double best_sq = cluster_gap_sq_m2_;
    std::size_t kept = 0;
    for (std::int32_t o : open_) {
      const Cluster& tail = clusters_[work_objects_[o].last_cluster];
      if (tail.run != cl.run || cl.first_pos > work_objects_[o].reach_pos) {
        continue;  // Closed for good: later clusters are even further away.
      }
      open_[kept++] = o;
      const double d_sq = gap_sq_between(tail, cl);
      if (d_sq <= best_sq) {
        best_sq = d_sq;
        best = o;
      }
    }
    open_.resize(kept);
    if (best < 0) {
      open_.push_back(new_object(c));
      continue;
    }
    Object& o = work_objects_[best];
    o.last_cluster = c;
    o.reach_pos = reach_of(c);
    o.count += cl.count;
    o.cluster_count += 1;
    o.sum_x += cl.sum_x;
    o.sum_y += cl.sum_y;
    object_of_cluster_[c] = best;
  }

  // Across the seam of a full circle: objects still open at the end of the pass may continue into
  // objects that start at the beginning of it.
  if (!seam_continuous) return;
  for (std::int32_t t : open_) {
    Object& tail_obj = work_objects_[t];
    const Cluster& tail = clusters_[tail_obj.last_cluster];
    if (tail.run != final_run) continue;  // A masked sector lies between it and the seam.
    std::int32_t best = -1;
    double best_sq = cluster_gap_sq_m2_;
    for (std::int32_t c = 0; c < cluster_count; ++c) {
      const Cluster& head = clusters_[c];
      if (head.run != 0 || head.first_pos + n > tail_obj.reach_pos) {
        break;
      }
      const std::int32_t h = object_of_cluster_[c];
      if (h == t || !work_objects_[h].alive || work_objects_[h].first_cluster != c) continue;
      const double d_sq = gap_sq_between(tail, head);
      if (d_sq <= best_sq) {
        best_sq = d_sq;
        best = h;
      }
    }
    if (best < 0) continue;
    // The tail object absorbs the head object: it now runs from its own first edge over the seam.
    Object& head_obj = work_objects_[best];
    tail_obj.last_cluster = head_obj.last_cluster;
    tail_obj.reach_pos = head_obj.reach_pos + n;
    tail_obj.count += head_obj.count;
    tail_obj.cluster_count += head_obj.cluster_count;
    tail_obj.sum_x += head_obj.sum_x;
    tail_obj.sum_y += head_obj.sum_y;
    head_obj.alive = false;
    for (std::int32_t& owner : object_of_cluster_) {
      if (owner == best) owner = t;
    }
  }
}

EdgeNeighbour Segmenter::neighbour_of(const LaserScan& scan, std::int32_t beam, int step) const {
  const auto n = static_cast<std::int32_t>(scan.size());
  std::int32_t j = beam + step;
  if (j < 0 || j >= n) {
    if (!full_circle_) return EdgeNeighbour::kFieldOfViewEnd;
    j = (j + n) % n;
  }
  if (masked_[j] != 0) return EdgeNeighbour::kMaskedSector;
  if (!scan.is_valid(j)) return EdgeNeighbour::kInvalid;
  return scan.ranges_m[j] < scan.ranges_m[beam] ? EdgeNeighbour::kCloser : EdgeNeighbour::kFarther;
}

// segmentation.min_width_m lowers N_min only within this share of the scanner's range_max.
constexpr double kMinWidthRangeShare = 0.8;

std::int32_t Segmenter::min_points_of(const LaserScan& scan, const Object& obj,
                                      const SeenBefore& seen_before) const {
  const std::int32_t n_min = config_.min_points;
  if (!(config_.min_width_m > 0.0) || n_min <= 2 || obj.count >= n_min) return n_min;
  // The beams an object min_width_m wide covers at the range of this one's centroid.
  const double range =
      std::hypot(obj.sum_x, obj.sum_y) / static_cast<double>(std::max<std::int32_t>(obj.count, 1));
  const double covered = config_.min_width_m / (range * cached_increment_rad_);
  if (!(covered < static_cast<double>(n_min))) return n_min;  // Also a range of 0 (inf, NaN).
  // Not near the end of the scanner's reach, where returns are weak and come and go:
  // person_following_outdoor_1's 5.6 m scanner returns runs of 1-4 beams at 4-5.6 m among beams
  // that return nothing, in the same places scan after scan (so "seen before" below admits them).
  if (!(range <= kMinWidthRangeShare * static_cast<double>(scan.range_max_m))) return n_min;
  // Only a thing that stands out whole in front of what is beside it (a leg against the far
  // wall or against nothing): a piece of a wall seen at a slant, or a thing cut by the view's
  // end or by something nearer, is no object below min_points. Nor is one beside a beam that
  // measured nothing usable (NaN, or below range_min: a scanner's error code), which says
  // nothing of what is there: negative_2's lasers read 0 on a fifth of their beams, scattered
  // over walls at 3-7 m, whose pieces between such beams were taken for legs.
  const auto stands_out = [&](std::int32_t beam, int step) {
    const EdgeNeighbour e = neighbour_of(scan, beam, step);
    if (e == EdgeNeighbour::kFarther) return true;
    if (e != EdgeNeighbour::kInvalid) return false;
    const auto n = static_cast<std::int32_t>(scan.size());
    return scan.ranges_m[static_cast<std::size_t>((beam + step + n) % n)] > scan.range_max_m;
  };
  if (!stands_out(clusters_[obj.first_cluster].first_beam, -1) ||
      !stands_out(clusters_[obj.last_cluster].last_beam, +1)) {
    return n_min;
  }
  if (seen_before) {
    const double count = static_cast<double>(obj.count);
    if (!seen_before(Eigen::Vector2d(obj.sum_x / count, obj.sum_y / count))) return n_min;
  }
  return std::max<std::int32_t>(2, static_cast<std::int32_t>(std::lround(covered)));
}

void Segmenter::write_objects(const LaserScan& scan, Segmentation& out,
                              const SeenBefore& seen_before) {
  // Objects with at least N_min points survive, ordered by first beam.
  order_.clear();
  for (std::int32_t o = 0; o < static_cast<std::int32_t>(work_objects_.size()); ++o) {
    const Object& obj = work_objects_[o];
    if (obj.alive && obj.count >= min_points_of(scan, obj, seen_before)) order_.push_back(o);
    if (obj.alive && obj.cluster_count > 1) out.merges += obj.cluster_count - 1;
  }
  std::sort(order_.begin(), order_.end(), [&](std::int32_t a, std::int32_t b) {
    return clusters_[work_objects_[a].first_cluster].first_beam <
           clusters_[work_objects_[b].first_cluster].first_beam;
  });

  std::vector<std::int32_t>& final_id = open_;  // Reused: object index -> output index.
  final_id.assign(work_objects_.size(), kLabelNoise);
  out.objects.resize(order_.size());
  for (std::size_t k = 0; k < order_.size(); ++k) {
    const Object& obj = work_objects_[order_[k]];
    const Cluster& first = clusters_[obj.first_cluster];
    const Cluster& last = clusters_[obj.last_cluster];
    ScanObject& so = out.objects[k];
    so.first_beam = first.first_beam;
    so.last_beam = last.last_beam;
    so.point_count = obj.count;
    so.cluster_count = obj.cluster_count;
    so.first_point_m = {first.first_x, first.first_y};
    so.last_point_m = {last.last_x, last.last_y};
    so.centroid_m = {obj.sum_x / obj.count, obj.sum_y / obj.count};
    so.before_first = neighbour_of(scan, so.first_beam, -1);
    so.after_last = neighbour_of(scan, so.last_beam, +1);
    final_id[order_[k]] = static_cast<std::int32_t>(k);
  }

  cluster_label_.resize(clusters_.size());
  for (std::size_t c = 0; c < clusters_.size(); ++c) {
    cluster_label_[c] = final_id[object_of_cluster_[c]];
  }
  std::int32_t noise = 0;
  for (std::int32_t& label : out.beam_labels) {
    if (label >= 0) {
      label = cluster_label_[label];
      noise += label == kLabelNoise ? 1 : 0;
    }
  }
  out.noise_beams = noise;
}

}  // namespace dispel
