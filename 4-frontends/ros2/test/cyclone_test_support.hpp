#pragma once
// For the ROS 2 tests on Cyclone DDS: readers of Cyclone's own types (from idlc), the tests'
// second opinion on dispel's raw CDR.
#include <dds/dds.h>

#include <string>

#include "dispel/ros2/dds.hpp"

namespace dispel::ros2::cyclone_test {

/// A reader of Cyclone's type @p descriptor on the DDS topic @p topic: reliable, keep all, and
/// transient local when asked (to get what was written before it). Negative: DDS's error.
inline dds_entity_t typed_reader(const Participant& participant,
                                 const dds_topic_descriptor_t* descriptor, const std::string& topic,
                                 bool transient_local) {
  const dds_entity_t t =
      dds_create_topic(participant.handle(), descriptor, topic.c_str(), nullptr, nullptr);
  if (t < 0) return t;
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  if (transient_local) dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
  const dds_entity_t r = dds_create_reader(participant.handle(), t, qos, nullptr);
  dds_delete_qos(qos);
  return r;
}

}  // namespace dispel::ros2::cyclone_test
