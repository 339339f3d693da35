#pragma once
/// @file
/// Static/dynamic classification of tracked objects by accumulated evidence (thesis 3.2.4).

#include <cstdint>

namespace dispel {

/// What a tracked object is believed to be.
enum class ObjectClass : std::uint8_t {
  kStatic,   ///< Kept in the filtered scan.
  kDynamic,  ///< Removed; for good once reached.
  kUnknown,  ///< Removed too; only under the presumption of guilt, until proven static.
};

/// How new objects are treated.
enum class Presumption {
  /// POI: every object starts static and becomes dynamic once its dynamic weight exceeds L_d.
  kInnocence,
  /// POG: every object starts unknown (removed); it becomes static when its static weight reaches
  /// L_s and dynamic when its dynamic weight reaches L_d.
  kGuilt,
};

/// Parameters of the classification. The defaults are dispel's; thesis_config()
/// (dynamic_filter_config.hpp) has the thesis's (Appendix A and its rules).
struct ClassificationConfig {
  Presumption presumption = Presumption::kInnocence;
  /// L_v: an object is moving in a scan when its speed (the lowest of its three points') is above.
  double speed_limit_mps = 0.08;
  /// L_d: dynamic weight limit. dispel's 8 (the thesis's 18) is 0.4 s of motion at 20 Hz once the
  /// velocity estimate is right.
  int dynamic_weight_limit = 8;
  /// L_s: static weight limit (POG only).
  int static_weight_limit = 50;
  /// The three points move "in a similar direction" when every two of their velocities are at
  /// most this far apart in direction. Otherwise the scan gives no evidence.
  double max_direction_difference_rad = 0.785398163397448;  // 45 degrees.
  /// Objects whose edge points are farther apart than this never gain dynamic weight (walls,
  /// racks). 3 m lets a forklift seen from the side through.
  double max_dynamic_extent_m = 3.0;
  /// Beyond the thesis: each slow scan takes one from the dynamic weight (not below 0) until the
  /// object is dynamic. The thesis only adds; with this on (the default) measurement noise that now
  /// and then pushes a wall over L_v cannot add up over minutes to make the wall dynamic.
  bool slow_scans_reduce_dynamic_weight = true;
  /// Beyond the thesis: a dynamic object that has been slow for this many scans in a row is static
  /// again (0: never, the thesis's "dynamic for good"). It keeps a parked vehicle or a long-waiting
  /// person out of the scan for a while, and it undoes a dynamic track that has drifted onto a
  /// wall. 100 scans is 5 s at the thesis's 20 Hz.
  int still_scans_to_static = 100;
  /// Beyond the thesis: a dynamic object that has stayed within 0.15 m of the place where it was
  /// seen again after scans unseen, for this long, with no other dynamic track beside it (within
  /// tracking.companion_distance_m), is static again (0: never). A person who stops keeps the
  /// track of the other leg beside each leg, and one who pauses in view was not unseen first; a
  /// dynamic track that lost its walker and was matched to something standing there (a low thing
  /// first seen up close, its gate widened by the scans it was unseen) has neither, and it would
  /// keep that thing's beams out of the scan and the map for still_scans_to_static scans.
  double still_alone_to_static_s = 1.0;
  /// A scan where the object's point count changed by more than this factor since the last scan
  /// gives no evidence (a merge, a split, or an occlusion starting).
  double max_point_count_ratio = 1.5;

  /// Throws std::invalid_argument naming the first bad field and its value.
  void validate() const;
};

/// What one scan says about an object's motion.
enum class MotionEvidence : std::uint8_t {
  kNone,  ///< Nothing usable (directions disagree, size jumped, ambiguous and fast, ...).
  kSlow,  ///< Speed at or below L_v.
  kFast,  ///< Speed above L_v, the three points agree, and the object may be dynamic.
};

/// The evolving belief about one object.
struct ClassState {
  ObjectClass object_class = ObjectClass::kStatic;
  std::int32_t dynamic_weight = 0;
  std::int32_t static_weight = 0;
  std::int32_t still_scans = 0;  ///< Slow scans in a row while dynamic.
};

/// The belief about an object seen for the first time.
ClassState initial_class_state(const ClassificationConfig& config);

/// One scan's update of the weights and the class (pure function).
ClassState update_class_state(ClassState state, MotionEvidence evidence,
                              const ClassificationConfig& config);

}  // namespace dispel
