// ROS 2 over Cyclone DDS: names, and messages through DDS between dispel's raw CDR and Cyclone's
// own serialisation of the ROS 2 IDL (ros2_laser_scan.idl, compiled by Cyclone's idlc): the same
// bytes both ways, so what dispel writes is what a node built on the type from its IDL reads.
//
// Every test is its own process (ctest), in a DDS domain of its own (from its process id) on the
// loopback, so tests run side by side do not see each other. Endpoints in one process find each
// other without the network; the waits below bound how long a failure takes to show, not how
// long a pass takes (a match is normally there within milliseconds; 20 s is for a loaded
// machine, where a thread may wait seconds for a core).
#include "dispel/ros2/dds.hpp"

#include <dds/dds.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>

#include "cyclone_test_support.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "dispel/ros2/graph.hpp"
#include "live_test_support.hpp"
#include "rmw_dds_common_humble.h"
#include "ros2_laser_scan.h"

namespace dispel::ros2 {
namespace {

using io::ScanMessage;
using io::Stamp;

using cyclone_test::typed_reader;
using live_test::eventually;

// Domains 50-99: their ports (7400 + 250 d) stay below Linux's ephemeral range (32768 on).
int test_domain() { return 50 + static_cast<int>(::getpid() % 50); }

// A topic of this process alone: tests run side by side may share a domain.
std::string own(const std::string& topic) { return topic + "_p" + std::to_string(::getpid()); }

class Ros2Dds : public ::testing::Test {
 protected:
  void SetUp() override {
    // The loopback only, without multicast: nothing leaves the machine.
    ::setenv("CYCLONEDDS_URI",
             "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
             "<AllowMulticast>false</AllowMulticast></General>",
             1);
  }
};

ScanMessage example_scan() {
  ScanMessage m;
  m.header.stamp = Stamp::from_seconds(1700000000.25);
  m.header.frame_id = "laser_front";
  m.scan.stamp_s = m.header.stamp.seconds();
  m.scan.angle_min_rad = -1.5;
  m.scan.angle_increment_rad = 0.5;
  m.angle_max = 1.5F;
  m.scan.range_min_m = 0.1F;
  m.scan.range_max_m = 30.0F;
  m.scan.ranges_m = {1.0F, 2.5F, std::nanf(""), 4.0F, 30.5F, 0.05F, 7.0F};
  m.scan.intensities = {10, 20, 30, 40, 50, 60, 70};
  return m;
}

TEST(Ros2Names, TopicsAndTypesAsRos2MangesThem) {
  EXPECT_EQ(dds_topic_name("/scan"), "rt/scan");
  EXPECT_EQ(dds_topic_name("/robot_1/scan_filtered"), "rt/robot_1/scan_filtered");
  for (const char* bad : {"scan", "/", "", "/a//b", "/a/", "/1scan", "/sc an", "/a/9"}) {
    EXPECT_THROW(dds_topic_name(bad), DdsError) << bad;
  }
  EXPECT_EQ(dds_type_name("sensor_msgs/msg/LaserScan"), "sensor_msgs::msg::dds_::LaserScan_");
  EXPECT_EQ(dds_type_name("tf2_msgs/TFMessage"), "tf2_msgs::msg::dds_::TFMessage_");
  for (const char* bad : {"LaserScan", "sensor_msgs/srv/X", "a/msg/b/c", "a//b", "a/b-c"}) {
    EXPECT_THROW(dds_type_name(bad), DdsError) << bad;
  }
}

TEST(Ros2Names, DomainFromTheEnvironment) {
  ::unsetenv("ROS_DOMAIN_ID");
  EXPECT_EQ(domain_from_environment(), 0);
  ::setenv("ROS_DOMAIN_ID", "42", 1);
  EXPECT_EQ(domain_from_environment(), 42);
  for (const char* bad : {"233", "-1", "4x", "1e2", "99999999999"}) {
    ::setenv("ROS_DOMAIN_ID", bad, 1);
    try {
      domain_from_environment();
      ADD_FAILURE() << bad;
    } catch (const DdsError& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string("ROS_DOMAIN_ID='") + bad + "' is not an integer from 0 to 232");
    }
  }
  ::unsetenv("ROS_DOMAIN_ID");
  EXPECT_THROW(Participant(233), DdsError);
}

// dispel writes a scan as raw CDR (io::encode_ros2); a reader of Cyclone's own type from the
// ROS 2 IDL, in a participant of its own, gets every field; a raw reader gets the same bytes.
TEST_F(Ros2Dds, RawCdrIsWhatCyclonesTypeFromTheRos2IdlReads) {
  Participant ours(test_domain());
  Participant theirs(test_domain());
  Writer writer(ours, own("/scan"), "sensor_msgs/msg/LaserScan", Qos::defaults());
  Reader raw(ours, own("/scan"), "sensor_msgs/msg/LaserScan", Qos::sensor_data());
  const dds_entity_t typed =
      typed_reader(theirs, &sensor_msgs_msg_dds__LaserScan__desc, "rt" + own("/scan"), false);
  ASSERT_GT(typed, 0);
  ASSERT_TRUE(eventually([&] { return writer.matches().current == 2; }))
      << writer.matches().current;

  const ScanMessage scan = example_scan();
  const std::vector<std::uint8_t> bytes = io::encode_ros2(scan);
  writer.write(bytes);

  std::vector<std::vector<std::uint8_t>> got;
  ASSERT_TRUE(eventually([&] {
    for (auto& b : raw.take(0.01)) got.push_back(std::move(b));
    return !got.empty();
  }));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], bytes);

  void* samples[1] = {nullptr};
  dds_sample_info_t info[1];
  dds_return_t n = 0;
  ASSERT_TRUE(eventually([&] {
    n = dds_take(typed, samples, info, 1, 1);
    return n != 0;
  }));
  ASSERT_EQ(n, 1);
  ASSERT_TRUE(info[0].valid_data);
  const auto* s = static_cast<const sensor_msgs_msg_dds__LaserScan_*>(samples[0]);
  EXPECT_EQ(s->header_.stamp_.sec_, 1700000000);
  EXPECT_EQ(s->header_.stamp_.nanosec_, 250000000u);
  EXPECT_STREQ(s->header_.frame_id_, "laser_front");
  EXPECT_EQ(s->angle_min_, -1.5F);
  EXPECT_EQ(s->angle_max_, 1.5F);
  EXPECT_EQ(s->angle_increment_, 0.5F);
  EXPECT_EQ(s->range_max_, 30.0F);
  ASSERT_EQ(s->ranges_._length, scan.scan.ranges_m.size());
  ASSERT_EQ(s->intensities_._length, scan.scan.intensities.size());
  for (std::size_t k = 0; k < scan.scan.ranges_m.size(); ++k) {
    if (std::isnan(scan.scan.ranges_m[k])) {
      EXPECT_TRUE(std::isnan(s->ranges_._buffer[k])) << k;
    } else {
      EXPECT_EQ(s->ranges_._buffer[k], scan.scan.ranges_m[k]) << k;
    }
    EXPECT_EQ(s->intensities_._buffer[k], scan.scan.intensities[k]) << k;
  }
  dds_return_loan(typed, samples, n);
}

// The other way: Cyclone serialises its type; dispel's raw reader gets the bytes io::encode_ros2
// makes of the same scan, and decodes them to it.
TEST_F(Ros2Dds, CyclonesSerialisationOfTheRos2IdlIsDispelsCdr) {
  Participant theirs(test_domain());
  Participant ours(test_domain());
  Reader raw(ours, own("/scan_in"), "sensor_msgs/LaserScan", Qos::sensor_data());
  const dds_entity_t topic =
      dds_create_topic(theirs.handle(), &sensor_msgs_msg_dds__LaserScan__desc,
                       ("rt" + own("/scan_in")).c_str(), nullptr, nullptr);
  ASSERT_GT(topic, 0);
  const dds_entity_t typed = dds_create_writer(theirs.handle(), topic, nullptr, nullptr);
  ASSERT_GT(typed, 0);
  ASSERT_TRUE(eventually([&] { return raw.matches().current == 1; }));

  const ScanMessage scan = example_scan();
  float ranges[7];
  float intensities[7];
  for (std::size_t k = 0; k < 7; ++k) {
    ranges[k] = scan.scan.ranges_m[k];
    intensities[k] = scan.scan.intensities[k];
  }
  sensor_msgs_msg_dds__LaserScan_ s{};
  s.header_.stamp_.sec_ = 1700000000;
  s.header_.stamp_.nanosec_ = 250000000;
  s.header_.frame_id_ = const_cast<char*>("laser_front");
  s.angle_min_ = -1.5F;
  s.angle_max_ = 1.5F;
  s.angle_increment_ = 0.5F;
  s.range_min_ = 0.1F;
  s.range_max_ = 30.0F;
  s.ranges_ = {7, 7, ranges, false};
  s.intensities_ = {7, 7, intensities, false};
  ASSERT_EQ(dds_write(typed, &s), DDS_RETCODE_OK);

  std::vector<std::vector<std::uint8_t>> got;
  ASSERT_TRUE(eventually([&] {
    for (auto& b : raw.take(0.01)) got.push_back(std::move(b));
    return !got.empty();
  }));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], io::encode_ros2(scan));
  const ScanMessage back = io::decode_ros2_scan(got[0].data(), got[0].size());
  EXPECT_EQ(back.header.frame_id, "laser_front");
  EXPECT_EQ(back.scan.ranges_m.size(), 7u);
}

// ROS 2's QoS rules as DDS applies them: a reliable writer serves a best-effort (sensor data)
// reader; a best-effort writer cannot serve a reliable reader, and both ends report it, naming
// the policy. A transient-local writer (/tf_static) gives a reader that comes later its sample.
TEST_F(Ros2Dds, QosMatchesAsRos2sAndAMismatchIsReported) {
  Participant p(test_domain());
  Writer best_effort(p, own("/points"), "sensor_msgs/msg/LaserScan", Qos::sensor_data());
  Reader reliable(p, own("/points"), "sensor_msgs/msg/LaserScan", Qos::defaults());
  ASSERT_TRUE(eventually([&] { return reliable.matches().incompatible >= 1; }));
  EXPECT_EQ(reliable.matches().current, 0);
  EXPECT_EQ(reliable.matches().last_incompatible_policy, "reliability");
  ASSERT_TRUE(eventually([&] { return best_effort.matches().incompatible >= 1; }));
  EXPECT_EQ(best_effort.matches().last_incompatible_policy, "reliability");

  const ScanMessage scan = example_scan();
  Writer latched(p, own("/tf_like"), "sensor_msgs/msg/LaserScan", Qos::tf_static_publisher());
  latched.write(io::encode_ros2(scan));
  Reader late(p, own("/tf_like"), "sensor_msgs/msg/LaserScan", Qos::tf_static_subscriber());
  std::vector<std::vector<std::uint8_t>> got;
  ASSERT_TRUE(eventually([&] {
    for (auto& b : late.take(0.01)) got.push_back(std::move(b));
    return !got.empty();
  }));
  EXPECT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], io::encode_ros2(scan));
  EXPECT_EQ(late.matches().current, 1);
}

// The graph's sample (ros_discovery_info) as ROS 2 Humble's RMW reads it: Cyclone's type from
// rmw_dds_common's Humble IDL (rmw_dds_common_humble.idl) gets every field. Iron's layout is the
// same with 16-byte gids.
TEST_F(Ros2Dds, TheGraphSampleIsWhatRos2sGraphTypeReads) {
  Participant ours(test_domain());
  Participant theirs(test_domain());
  Guid participant{}, reader{}, writer_a{}, writer_b{};
  for (std::uint8_t k = 0; k < 16; ++k) {
    participant[k] = k;
    reader[k] = static_cast<std::uint8_t>(0x10 + k);
    writer_a[k] = static_cast<std::uint8_t>(0x20 + k);
    writer_b[k] = static_cast<std::uint8_t>(0x30 + k);
  }
  const NodeEntities node{"/", "dispel_filter", {reader}, {writer_a, writer_b}};
  const std::string topic = "ros_discovery_info_p" + std::to_string(::getpid());
  Writer graph(ours, DdsTopic{topic, discovery_topic().type}, discovery_qos());
  graph.write(encode_participant_entities(participant, {node}, GidLayout::kHumble));
  // Transient local: a reader that comes later gets it, as ROS 2's tools do.
  const dds_entity_t r =
      typed_reader(theirs, &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc, topic, true);
  ASSERT_GT(r, 0);
  void* samples[1] = {nullptr};
  dds_sample_info_t info[1];
  dds_return_t n = 0;
  ASSERT_TRUE(eventually([&] {
    n = dds_take(r, samples, info, 1, 1);
    return n != 0;
  }));
  ASSERT_EQ(n, 1);
  const auto* p = static_cast<const rmw_dds_common_msg_dds__ParticipantEntitiesInfo_*>(samples[0]);
  for (std::size_t k = 0; k < 24; ++k) {
    EXPECT_EQ(p->gid_.data_[k], k < 16 ? participant[k] : 0) << k;  // Zero-padded.
  }
  ASSERT_EQ(p->node_entities_info_seq_._length, 1u);
  const auto& e = p->node_entities_info_seq_._buffer[0];
  EXPECT_STREQ(e.node_namespace_, "/");
  EXPECT_STREQ(e.node_name_, "dispel_filter");
  ASSERT_EQ(e.reader_gid_seq_._length, 1u);
  ASSERT_EQ(e.writer_gid_seq_._length, 2u);
  EXPECT_EQ(e.reader_gid_seq_._buffer[0].data_[0], 0x10);
  EXPECT_EQ(e.writer_gid_seq_._buffer[1].data_[15], 0x3f);
  EXPECT_EQ(e.writer_gid_seq_._buffer[1].data_[16], 0);
  dds_return_loan(r, samples, n);

  // Iron on: 16-byte gids, so 8 bytes fewer per gid (4 gids) than Humble's.
  EXPECT_EQ(encode_participant_entities(participant, {node}, GidLayout::kHumble).size() -
                encode_participant_entities(participant, {node}, GidLayout::kIron).size(),
            4u * 8u);
  EXPECT_EQ(gid_layout_named("jazzy"), GidLayout::kIron);
  EXPECT_EQ(gid_layout_named("humble"), GidLayout::kHumble);
  EXPECT_THROW(gid_layout_named("foxy2"), DdsError);
  EXPECT_THROW(encode_participant_entities(participant, {{"/", std::string(257, 'n'), {}, {}}},
                                           GidLayout::kIron),
               DdsError);
}

TEST_F(Ros2Dds, BadInputIsRefusedWithItsName) {
  Participant p(test_domain());
  Writer w(p, own("/scan"), "sensor_msgs/msg/LaserScan", Qos::defaults());
  try {
    w.write({1, 2});
    FAIL() << "written";
  } catch (const DdsError& e) {
    EXPECT_EQ(std::string(e.what()),
              "a message to write is not CDR with its encapsulation header (2 bytes)");
  }
  EXPECT_THROW(w.write({0, 7, 0, 0}), DdsError);  // Not XCDR1.
  Qos zero = Qos::defaults();
  zero.depth = 0;
  EXPECT_THROW(Reader(p, own("/x"), "sensor_msgs/msg/LaserScan", zero), DdsError);
}

}  // namespace
}  // namespace dispel::ros2
