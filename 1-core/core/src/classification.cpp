#include "dispel/core/classification.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "dispel/core/invalid_field.hpp"

namespace dispel {
namespace {

[[noreturn]] void reject(const char* field, double value, const char* rule) {
  reject_field(std::string("classification.") + field, value, rule);
}

}  // namespace

void ClassificationConfig::validate() const {
  if (presumption != Presumption::kInnocence && presumption != Presumption::kGuilt) {
    reject("presumption", static_cast<int>(presumption), "innocence or guilt");
  }
  if (!std::isfinite(speed_limit_mps) || speed_limit_mps < 0.0) {
    reject("speed_limit_mps", speed_limit_mps, "a finite number >= 0");
  }
  if (dynamic_weight_limit < 1) reject("dynamic_weight_limit", dynamic_weight_limit, ">= 1");
  if (static_weight_limit < 1) reject("static_weight_limit", static_weight_limit, ">= 1");
  if (!std::isfinite(max_direction_difference_rad) || max_direction_difference_rad <= 0.0 ||
      max_direction_difference_rad > 3.14159265358979323846) {
    reject("max_direction_difference_rad", max_direction_difference_rad, "in (0, pi]");
  }
  if (!(max_dynamic_extent_m > 0.0)) {
    reject("max_dynamic_extent_m", max_dynamic_extent_m, "> 0");
  }
  if (still_scans_to_static < 0) reject("still_scans_to_static", still_scans_to_static, ">= 0");
  if (!(still_alone_to_static_s >= 0.0 && still_alone_to_static_s <= 3600.0)) {
    reject("still_alone_to_static_s", still_alone_to_static_s, "in [0, 3600]");
  }
  if (!(max_point_count_ratio >= 1.0)) {
    reject("max_point_count_ratio", max_point_count_ratio, ">= 1");
  }
}

ClassState initial_class_state(const ClassificationConfig& config) {
  ClassState s;
  s.object_class =
      config.presumption == Presumption::kGuilt ? ObjectClass::kUnknown : ObjectClass::kStatic;
  return s;
}

ClassState update_class_state(ClassState s, MotionEvidence evidence,
                              const ClassificationConfig& config) {
  if (s.object_class == ObjectClass::kDynamic) {
    if (evidence == MotionEvidence::kFast) s.still_scans = 0;
    if (evidence == MotionEvidence::kSlow && config.still_scans_to_static > 0 &&
        ++s.still_scans >= config.still_scans_to_static) {
      s = ClassState{};  // Static, with its weights starting afresh.
    }
    return s;
  }
  if (evidence == MotionEvidence::kNone) return s;
  if (evidence == MotionEvidence::kSlow && config.slow_scans_reduce_dynamic_weight) {
    s.dynamic_weight = std::max(0, s.dynamic_weight - 1);
  }
  if (config.presumption == Presumption::kInnocence) {
    if (evidence == MotionEvidence::kFast && ++s.dynamic_weight > config.dynamic_weight_limit) {
      s.object_class = ObjectClass::kDynamic;
    }
    return s;
  }
  // Presumption of guilt: evidence moves weight between the two sides.
  if (evidence == MotionEvidence::kFast) {
    ++s.dynamic_weight;
    s.static_weight = std::max(0, s.static_weight - 1);
  } else {
    ++s.static_weight;
  }
  if (s.dynamic_weight >= config.dynamic_weight_limit) {
    s.object_class = ObjectClass::kDynamic;
  } else if (s.static_weight >= config.static_weight_limit) {
    s.object_class = ObjectClass::kStatic;
  }
  return s;
}

}  // namespace dispel
