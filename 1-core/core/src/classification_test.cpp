#include "dispel/core/classification.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace dispel {
namespace {

TEST(Classification, InnocenceStartsStaticAndTurnsDynamicPastTheLimitForGood) {
  ClassificationConfig config;
  config.slow_scans_reduce_dynamic_weight = false;  // The thesis's rules.
  config.still_scans_to_static = 0;
  ClassState s = initial_class_state(config);
  EXPECT_EQ(s.object_class, ObjectClass::kStatic);
  for (int k = 1; k <= config.dynamic_weight_limit; ++k) {
    s = update_class_state(s, MotionEvidence::kFast, config);
    s = update_class_state(s, MotionEvidence::kSlow, config);  // Slow scans do not undo it.
    s = update_class_state(s, MotionEvidence::kNone, config);
    ASSERT_EQ(s.object_class, ObjectClass::kStatic) << "after " << k << " fast scans";
  }
  EXPECT_EQ(s.dynamic_weight, config.dynamic_weight_limit);
  s = update_class_state(s, MotionEvidence::kFast, config);
  EXPECT_EQ(s.object_class, ObjectClass::kDynamic);
  for (int k = 0; k < 500; ++k) s = update_class_state(s, MotionEvidence::kSlow, config);
  EXPECT_EQ(s.object_class, ObjectClass::kDynamic);
}

TEST(Classification, SlowScansTakeDynamicWeightAwaySoNoiseCannotAddUp) {
  const ClassificationConfig config;  // The default: slow scans reduce the dynamic weight.
  ClassState s = initial_class_state(config);
  // One fast scan in three, for minutes: a noisy wall. It never becomes dynamic.
  for (int k = 0; k < 3000; ++k) {
    s = update_class_state(s, k % 3 == 0 ? MotionEvidence::kFast : MotionEvidence::kSlow, config);
  }
  EXPECT_EQ(s.object_class, ObjectClass::kStatic);
  EXPECT_LE(s.dynamic_weight, 1);
  // A walker: L_d + 1 fast scans in a row.
  for (int k = 0; k <= config.dynamic_weight_limit; ++k) {
    s = update_class_state(s, MotionEvidence::kFast, config);
  }
  EXPECT_EQ(s.object_class, ObjectClass::kDynamic);
}

TEST(Classification, ADynamicObjectStillForLongEnoughIsStaticAgain) {
  const ClassificationConfig config;  // still_scans_to_static = 100.
  ClassState s = initial_class_state(config);
  for (int k = 0; k <= config.dynamic_weight_limit; ++k) {
    s = update_class_state(s, MotionEvidence::kFast, config);
  }
  ASSERT_EQ(s.object_class, ObjectClass::kDynamic);
  const int still = config.still_scans_to_static;
  for (int k = 1; k < still; ++k) s = update_class_state(s, MotionEvidence::kSlow, config);
  EXPECT_EQ(s.object_class, ObjectClass::kDynamic);
  s = update_class_state(s, MotionEvidence::kFast, config);  // It moved: count again.
  for (int k = 1; k < still; ++k) {
    s = update_class_state(s, MotionEvidence::kSlow, config);
    s = update_class_state(s, MotionEvidence::kNone, config);  // No evidence: no change.
  }
  EXPECT_EQ(s.object_class, ObjectClass::kDynamic);
  s = update_class_state(s, MotionEvidence::kSlow, config);
  EXPECT_EQ(s.object_class, ObjectClass::kStatic);
  EXPECT_EQ(s.dynamic_weight, 0);
}

TEST(Classification, GuiltStartsUnknownAndNeedsLsSlowScansToBeStatic) {
  ClassificationConfig config;
  config.presumption = Presumption::kGuilt;
  ClassState s = initial_class_state(config);
  EXPECT_EQ(s.object_class, ObjectClass::kUnknown);
  for (int k = 1; k < config.static_weight_limit; ++k) {
    s = update_class_state(s, MotionEvidence::kSlow, config);
    ASSERT_EQ(s.object_class, ObjectClass::kUnknown);
  }
  s = update_class_state(s, MotionEvidence::kSlow, config);
  EXPECT_EQ(s.object_class, ObjectClass::kStatic);
}

TEST(Classification, GuiltFastScansTakeStaticWeightAwayAndReachDynamic) {
  ClassificationConfig config;
  config.presumption = Presumption::kGuilt;
  config.dynamic_weight_limit = 18;  // The thesis's L_d: more fast scans than the 10 slow ones.
  ClassState s = initial_class_state(config);
  for (int k = 0; k < 10; ++k) s = update_class_state(s, MotionEvidence::kSlow, config);
  s = update_class_state(s, MotionEvidence::kFast, config);
  EXPECT_EQ(s.static_weight, 9);
  EXPECT_EQ(s.dynamic_weight, 1);
  for (int k = 1; k < config.dynamic_weight_limit; ++k) {
    s = update_class_state(s, MotionEvidence::kFast, config);
  }
  EXPECT_EQ(s.object_class, ObjectClass::kDynamic);
  EXPECT_EQ(s.static_weight, 0);
}

TEST(Classification, GuiltStaticObjectThatStartsMovingBecomesDynamic) {
  ClassificationConfig config;
  config.presumption = Presumption::kGuilt;
  ClassState s = initial_class_state(config);
  for (int k = 0; k < config.static_weight_limit; ++k) {
    s = update_class_state(s, MotionEvidence::kSlow, config);
  }
  ASSERT_EQ(s.object_class, ObjectClass::kStatic);
  for (int k = 0; k < config.dynamic_weight_limit; ++k) {
    s = update_class_state(s, MotionEvidence::kFast, config);
  }
  EXPECT_EQ(s.object_class, ObjectClass::kDynamic);
}

TEST(ClassificationConfig, BadValuesAreRejectedByName) {
  ClassificationConfig c;
  EXPECT_NO_THROW(c.validate());
  c.speed_limit_mps = -0.1;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = ClassificationConfig{};
  c.dynamic_weight_limit = 0;
  try {
    c.validate();
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dynamic_weight_limit"), std::string::npos);
  }
  c = ClassificationConfig{};
  c.max_point_count_ratio = 0.5;
  EXPECT_THROW(c.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace dispel
