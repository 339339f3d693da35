// dispel-ros2 filter, live over DDS on the loopback: the test, a DDS participant of its own, plays
// the leg_tracker recording's scans (a stationary Hokuyo, people walking past) the way a ROS 2
// driver publishes them, and receives the node's <scan>_filtered and <scan>_labels; they must be
// what the shared runner makes of the same scans in-process, with the options `dispel filter
// --static-sensor --scale-to-scanner` gives it (the one road both take), scan for scan. Both QoS
// a driver may use on the scans: reliable (ROS 2's default) and best effort (sensor data). Then a
// publisher of /tf_static with a QoS the node cannot match: the node says so. Then SIGTERM: the
// node stops, exit 0, with its counts.
//
// No scheduling luck: the test sends a scan only once the node's outputs of the previous one are
// in (lock step), so the node's reliable writers never hold more than one sample for the test and
// no queue can overflow; and only once both ends of each topic have found each other (the
// node says when its ends have). The scans' DDS reader is best effort (what ROS 2 drivers'
// subscribers use) even for a reliable writer; on the loopback, with one sample in flight, nothing
// is lost (a lost sample would fail the test after kWaitS, not pass it). The waits (kWaitS) only
// bound how long a failure takes to show: discovery on the loopback takes milliseconds, a loaded
// machine may take seconds.
#include <dds/dds.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "cyclone_test_support.hpp"
#include "dispel/io/config_yaml.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "dispel/jobs/job.hpp"
#include "dispel/pipeline/scan_filter_runner.hpp"
#include "dispel/ros2/dds.hpp"
#include "dispel/ros2/graph.hpp"
#include "live_test_support.hpp"
#include "node_process.hpp"
#include "rmw_dds_common_humble.h"
#include "test_files.hpp"

namespace dispel::ros2 {
namespace {

using live_test::eventually;
using live_test::kLoopback;
using live_test::kWaitS;
using live_test::NodeProcess;

std::vector<io::ScanMessage> recorded_scans() {
  auto reader = jobs::open_recording(
      test::source_path("data/leg_tracker/demo_stationary_simple_environment.bag"));
  std::vector<io::ScanMessage> scans;
  reader->read({"/scan"}, [&](const io::RecordedMessage& m) {
    if (auto s = m.scan()) scans.push_back(*s);
  });
  return scans;
}

Guid guid_of(const dds_builtintopic_guid_t& g) {
  Guid out{};
  std::copy(std::begin(g.v), std::end(g.v), out.begin());
  return out;
}

bool listed(const rmw_dds_common_msg_dds__Gid_* gids, std::uint32_t n, const Guid& g) {
  for (std::uint32_t k = 0; k < n; ++k) {
    if (std::equal(g.begin(), g.end(), gids[k].data_)) return true;
  }
  return false;
}

// The node in ROS 2's graph, as `ros2 node list` reads it (ros_discovery_info in Humble's layout,
// Cyclone's type from rmw_dds_common's IDL): its name and namespace, and, as its own, the DDS
// reader the test's driver writes to and the writers the test's readers read from (their GUIDs
// as DDS discovery gave them to the test), under its participant's gid.
void check_graph(Participant& test, const std::string& node_name, Writer& driver, Reader& filtered,
                 Reader& labels) {
  const dds_entity_t r = cyclone_test::typed_reader(
      test, &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc, "ros_discovery_info", true);
  ASSERT_GT(r, 0);
  // Another process's node may share the domain (tests run side by side): this one's sample is
  // the one with its name.
  void* samples[1] = {nullptr};
  dds_sample_info_t info[1];
  const rmw_dds_common_msg_dds__ParticipantEntitiesInfo_* p = nullptr;
  ASSERT_TRUE(eventually([&] {
    while (dds_take(r, samples, info, 1, 1) == 1) {
      const auto* s =
          static_cast<const rmw_dds_common_msg_dds__ParticipantEntitiesInfo_*>(samples[0]);
      if (info[0].valid_data && s->node_entities_info_seq_._length == 1 &&
          node_name == s->node_entities_info_seq_._buffer[0].node_name_) {
        p = s;
        return true;
      }
      dds_return_loan(r, samples, 1);
    }
    return false;
  }));
  const auto& node = p->node_entities_info_seq_._buffer[0];
  EXPECT_STREQ(node.node_namespace_, "/");
  const auto matched_guid = [](dds_entity_t entity, bool publications, Guid& guid,
                               Guid& participant) {
    dds_instance_handle_t handle = 0;
    const dds_return_t found = publications ? dds_get_matched_publications(entity, &handle, 1)
                                            : dds_get_matched_subscriptions(entity, &handle, 1);
    if (found != 1) return false;
    dds_builtintopic_endpoint_t* e = publications
                                         ? dds_get_matched_publication_data(entity, handle)
                                         : dds_get_matched_subscription_data(entity, handle);
    if (e == nullptr) return false;
    guid = guid_of(e->key);
    participant = guid_of(e->participant_key);
    dds_builtintopic_free_endpoint(e);
    return true;
  };
  Guid g{}, owner{};
  ASSERT_TRUE(matched_guid(driver.handle(), false, g, owner));
  EXPECT_TRUE(listed(node.reader_gid_seq_._buffer, node.reader_gid_seq_._length, g));
  EXPECT_TRUE(std::equal(owner.begin(), owner.end(), p->gid_.data_));
  for (const std::uint8_t pad : std::vector<std::uint8_t>(p->gid_.data_ + 16, p->gid_.data_ + 24)) {
    EXPECT_EQ(pad, 0);
  }
  for (Reader* reader : {&filtered, &labels}) {
    ASSERT_TRUE(matched_guid(reader->handle(), true, g, owner));
    EXPECT_TRUE(listed(node.writer_gid_seq_._buffer, node.writer_gid_seq_._length, g));
  }
  EXPECT_EQ(node.reader_gid_seq_._length, 3u);  // The scans, /tf, /tf_static.
  EXPECT_EQ(node.writer_gid_seq_._length, 3u);  // The filtered scans, the labels, /diagnostics.
  dds_return_loan(r, samples, 1);
}

void play_and_compare(Qos scan_qos, const char* name) {
  SCOPED_TRACE(name);
  ::setenv("CYCLONEDDS_URI", kLoopback, 1);
  // Domains 10-49: their ports (7400 + 250 d) stay below Linux's ephemeral range (32768 on).
  const int domain = 10 + static_cast<int>(::getpid() % 40);
  const std::vector<io::ScanMessage> scans = recorded_scans();
  ASSERT_GT(scans.size(), 100u);

  // The reference: the runner as `dispel filter --static-sensor --scale-to-scanner` runs it,
  // with dispel's default configuration (`dispel filter` without --config).
  // The scan topic of this process alone: the live tests run side by side may share a domain.
  const std::string scan_topic = "/scan_p" + std::to_string(::getpid());
  const std::string params =
      "/**:\n  ros__parameters:\n    static_sensor: true\n    scale_to_scanner: true\n"
      "    ros_distro: humble\n    scan_topic: " +
      scan_topic + "\n";
  pipeline::ScanFilterRunnerOptions options;
  options.config = io::parse_filter_config("{}", "defaults");
  options.scale_to_scanner = true;
  options.static_sensor = true;
  pipeline::ScanFilterRunner reference(options);

  const std::string node_name = "dispel_filter_p" + std::to_string(::getpid());
  NodeProcess node("filter", params, node_name, domain);
  Participant test(domain);
  Writer driver(test, scan_topic, "sensor_msgs/msg/LaserScan", scan_qos);
  Reader filtered(test, scan_topic + "_filtered", "sensor_msgs/msg/LaserScan", Qos::defaults());
  Reader labels(test, scan_topic + "_labels", "sensor_msgs/msg/LaserScan", Qos::defaults());
  // Both ends of each topic must know the other before a sample can go: a best-effort reader
  // drops what comes from a writer it has not discovered yet, a volatile writer sends nothing to
  // a reader it has not. The test's ends say so themselves; the node's say so in its log.
  ASSERT_TRUE(eventually([&] {
    const std::string log = node.log();
    return driver.matches().current == 1 && filtered.matches().current == 1 &&
           labels.matches().current == 1 &&
           log.find(scan_topic + ": 1 publishers matched") != std::string::npos &&
           log.find(scan_topic + "_filtered: 1 subscribers matched") != std::string::npos &&
           log.find(scan_topic + "_labels: 1 subscribers matched") != std::string::npos;
  })) << node.log();

  check_graph(test, node_name, driver, filtered, labels);

  std::int64_t removed = 0;
  std::vector<double> round_trip_ms;  // Printed, not asserted: times belong in benchmarks.
  for (std::size_t k = 0; k < scans.size(); ++k) {
    const auto sent = std::chrono::steady_clock::now();
    driver.write(io::encode_ros2(scans[k]));
    std::vector<std::vector<std::uint8_t>> f, l;
    // Each wait wakes as its sample comes (a DDS wait set), so the time is the node's and DDS's.
    const auto deadline = sent + std::chrono::duration<double>(kWaitS);
    while ((f.empty() || l.empty()) && std::chrono::steady_clock::now() < deadline) {
      for (auto& b : filtered.take(f.empty() ? 0.05 : 0.0)) f.push_back(std::move(b));
      for (auto& b : labels.take(l.empty() ? 0.05 : 0.0)) l.push_back(std::move(b));
    }
    ASSERT_TRUE(!f.empty() && !l.empty()) << "scan " << k << "\n" << node.log();
    round_trip_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - sent).count());
    ASSERT_EQ(f.size(), 1u) << k;
    ASSERT_EQ(l.size(), 1u) << k;
    const FilterResult& expected =
        reference.process(scans[k].scan, scans[k].scan_time, Pose2{});  // Static: the identity.
    const io::ScanMessage want_filtered = io::filtered_message(scans[k], expected);
    const io::ScanMessage want_labels = io::labels_message(scans[k], expected);
    ASSERT_EQ(f[0], io::encode_ros2(want_filtered)) << "scan " << k;
    ASSERT_EQ(l[0], io::encode_ros2(want_labels)) << "scan " << k;
    for (float r : want_filtered.scan.ranges_m) removed += std::isnan(r) ? 1 : 0;
  }
  EXPECT_GT(removed, 0);  // The walkers: the comparison saw removals, not only a copy.
  std::sort(round_trip_ms.begin(), round_trip_ms.end());
  std::printf(
      "%zu scans, from the scan written to both outputs taken (the test and the node on the "
      "loopback): median %.2f ms, p99 %.2f ms, max %.2f ms\n",
      round_trip_ms.size(), round_trip_ms[round_trip_ms.size() / 2],
      round_trip_ms[round_trip_ms.size() * 99 / 100], round_trip_ms.back());

  // A /tf_static publisher the node cannot match (best effort, volatile): the node says so.
  Writer bad_tf(test, "/tf_static", "tf2_msgs/msg/TFMessage", Qos::sensor_data());
  ASSERT_TRUE(eventually([&] {
    return node.log().find(
               "warning: a publisher of /tf_static has a QoS this node cannot "
               "match") != std::string::npos;
  })) << node.log();

  EXPECT_EQ(node.stop(), 0) << node.log();
  const std::string counts =
      std::to_string(scans.size()) + " scans in, " + std::to_string(scans.size()) + " published";
  EXPECT_NE(node.log().find(counts), std::string::npos) << node.log();
}

TEST(Ros2FilterNodeLive, FiltersTheRecordingLikeDispelFilterWithAReliableDriver) {
  play_and_compare(Qos::defaults(), "reliable driver");
}

TEST(Ros2FilterNodeLive, FiltersTheRecordingLikeDispelFilterWithABestEffortDriver) {
  play_and_compare(Qos::sensor_data(), "best-effort driver");
}

TEST(Ros2FilterNodeLive, BadCommandLinesAndParameterFilesFailWithTheirName) {
  const auto run = [](const std::string& args) {
    // Under `timeout`: a node that would not exit fails the test instead of hanging it.
    const std::string command =
        "timeout -s KILL 60 " + std::string(DISPEL_ROS2_EXECUTABLE) + " " + args + " 2>&1";
    FILE* p = ::popen(command.c_str(), "r");
    std::string out;
    char buf[512];
    while (std::fgets(buf, sizeof buf, p) != nullptr) out += buf;
    const int status = ::pclose(p);
    return std::make_pair(WEXITSTATUS(status), out);
  };
  EXPECT_EQ(run("").first, 2);
  EXPECT_EQ(run("localize").first, 2);
  const auto missing = run("filter --params-file /nonexistent/p.yaml");
  EXPECT_EQ(missing.first, 2);
  EXPECT_NE(missing.second.find("/nonexistent/p.yaml"), std::string::npos) << missing.second;
  const std::string bad = test::write_text("bad.yaml", "queue_size: -3\n");
  const auto refused = run("filter --params-file " + bad);
  EXPECT_EQ(refused.first, 2);
  EXPECT_NE(refused.second.find("queue_size must be an integer from 1"), std::string::npos)
      << refused.second;
  const auto remap = run("filter --ros-args -r scan:=/front/scan");
  EXPECT_EQ(remap.first, 2);
  EXPECT_NE(remap.second.find("remapping 'scan:=/front/scan' is not supported"), std::string::npos)
      << remap.second;
  const auto namespaced = run("odometry --ros-args -r __ns:=/robot1");
  EXPECT_EQ(namespaced.first, 2);
  EXPECT_NE(namespaced.second.find("namespace '/robot1': only / is supported"), std::string::npos)
      << namespaced.second;
  const auto assignment = run("filter --ros-args -p queue_size:=0");
  EXPECT_EQ(assignment.first, 2);
  EXPECT_NE(assignment.second.find("-p queue_size:=0: queue_size must be"), std::string::npos)
      << assignment.second;
  ::setenv("ROS_DOMAIN_ID", "300", 1);
  const auto domain = run("filter");
  ::unsetenv("ROS_DOMAIN_ID");
  EXPECT_EQ(domain.first, 3);
  EXPECT_NE(domain.second.find("ROS_DOMAIN_ID='300'"), std::string::npos) << domain.second;
}

}  // namespace
}  // namespace dispel::ros2
