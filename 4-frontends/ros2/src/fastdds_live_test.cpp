// dispel-ros2 filter across DDS vendors: the node runs on Eclipse Cyclone DDS; this test's side is
// eProsima Fast DDS (the default RMW of ROS 2 Humble and Jazzy), with the message types that
// fastddsgen generates from the messages' IDL, filled field by field as a driver fills them.
// Nothing of dispel's own DDS or CDR code is on this side: what the node gets and gives is
// serialised and read by Fast DDS alone.
//
// The test plays the leg_tracker recording's scans (a Hokuyo standing still, people walking past)
// the way a ROS 2 robot publishes them: the laser's mount on /tf_static (robot_state_publisher:
// reliable, transient local, keep last 1), the robot's pose in odom on /tf at each scan's stamp
// (a driver's odometry TF: reliable, volatile, keep last 100), then the scan. It receives the
// node's <scan>_filtered as SLAM Toolbox subscribes to it (sensor data: best effort, keep last 5)
// and <scan>_labels with ROS 2's default QoS (reliable, keep last 10). Both must be what the
// shared runner (the road `dispel filter` takes) makes of the same scans at the sensor pose the
// transforms give, field for field and beam for beam. Both QoS a driver may publish scans with:
// reliable (ROS 2's default) and best effort (sensor data). Then a subscriber whose QoS the node
// cannot offer (transient local): both vendors report the mismatch. Then SIGTERM: exit 0.
//
// No scheduling luck: a scan is sent only once the node's outputs of the previous one are in
// (lock step), and once both ends of each topic have found each other. The node waits up to
// transform_timeout_s (set to kWaitS) for a scan's pose, so a scan that overtakes its transform
// on the wire still gets it. The waits bound how long a failure takes to show, nothing else.
//
// The poses are exact in binary (yaw 0, translations in quarters of a metre), so the sensor pose
// the node composes from the transforms and the one given to the reference are the same doubles.
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/recording.hpp"
#include "dispel/io/scenario_yaml.hpp"
#include "dispel/jobs/filter_job.hpp"
#include "dispel/jobs/job.hpp"
#include "dispel/jobs/sim_job.hpp"
#include "dispel/pipeline/scan_filter_runner.hpp"
#include "live_test_support.hpp"
#include "node_process.hpp"
#include "ros2_clockPubSubTypes.h"
#include "ros2_diagnosticsPubSubTypes.h"
#include "ros2_laser_scanPubSubTypes.h"
#include "ros2_tfPubSubTypes.h"
#include "test_files.hpp"

// Debian's Fast DDS 2.9 deletes its statistics readers through a base class of another size
// (AddressSanitizer: new-delete-type-mismatch in RTPSReader::~RTPSReader, allocated by
// StatisticsReaderImpl, when a participant is deleted), which would abort this test under ASan.
// That one check is off in this binary only, by ASan's default options (ASAN_OPTIONS still adds
// to them); the node, which has no Fast DDS in it, keeps every check.
extern "C" const char* __asan_default_options();
extern "C" const char* __asan_default_options() { return "new_delete_type_mismatch=0"; }

namespace dispel::ros2 {
namespace {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
using live_test::eventually;
using live_test::kLoopback;
using live_test::kWaitS;
using live_test::NodeProcess;
using FastScan = sensor_msgs::msg::dds_::LaserScan_;
using FastTf = tf2_msgs::msg::dds_::TFMessage_;

// ROS 2's QoS profiles in Fast DDS's terms (Fast DDS's own defaults differ: its writers are
// transient local, its readers best effort).
struct RosQos {
  bool reliable;
  bool transient_local;
  std::int32_t depth;
};
constexpr RosQos kDefaults{true, false, 10};     // rmw_qos_profile_default
constexpr RosQos kSensorData{false, false, 5};   // rmw_qos_profile_sensor_data
constexpr RosQos kTfStatic{true, true, 1};       // tf2_ros::StaticTransformBroadcaster
constexpr RosQos kTf{true, false, 100};          // tf2_ros::TransformBroadcaster
constexpr RosQos kLatchedReader{true, true, 1};  // asks for a durability the node does not offer
constexpr RosQos kClock{false, false, 1};        // rclcpp::ClockQoS

template <class Qos>
void set_ros_qos(Qos& q, const RosQos& p) {
  q.reliability().kind =
      p.reliable ? fdds::RELIABLE_RELIABILITY_QOS : fdds::BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind =
      p.transient_local ? fdds::TRANSIENT_LOCAL_DURABILITY_QOS : fdds::VOLATILE_DURABILITY_QOS;
  q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = p.depth;
}

// A ROS 2 process on Fast DDS: one participant on the loopback (UDP on 127.0.0.1 only, the node
// found by unicast), ROS 2's topic names ("rt" + the ROS name) and type names (the generated
// types' own).
class FastDdsProcess {
 public:
  explicit FastDdsProcess(int domain) {
    fdds::DomainParticipantQos qos;
    qos.name("dispel_fastdds_driver");
    qos.transport().use_builtin_transports = false;
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    qos.transport().user_transports.push_back(udp);
    eprosima::fastrtps::rtps::Locator_t peer;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(peer, 127, 0, 0, 1);
    qos.wire_protocol().builtin.initialPeersList.push_back(peer);
    participant_ = fdds::DomainParticipantFactory::get_instance()->create_participant(domain, qos);
    if (participant_ == nullptr) return;
    publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  }
  ~FastDdsProcess() {
    if (participant_ == nullptr) return;
    participant_->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
  FastDdsProcess(const FastDdsProcess&) = delete;
  FastDdsProcess& operator=(const FastDdsProcess&) = delete;

  bool ok() const { return participant_ != nullptr && publisher_ != nullptr && subscriber_; }

  template <class PubSubType>
  fdds::DataWriter* writer(const std::string& ros_topic, const RosQos& profile) {
    fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
    set_ros_qos(q, profile);
    return publisher_->create_datawriter(topic<PubSubType>(ros_topic), q);
  }
  void remove(fdds::DataWriter* w) { publisher_->delete_datawriter(w); }
  template <class PubSubType>
  fdds::DataReader* reader(const std::string& ros_topic, const RosQos& profile) {
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    set_ros_qos(q, profile);
    return subscriber_->create_datareader(topic<PubSubType>(ros_topic), q);
  }

 private:
  template <class PubSubType>
  fdds::Topic* topic(const std::string& ros_topic) {
    const auto found = topics_.find(ros_topic);
    if (found != topics_.end()) return found->second;
    fdds::TypeSupport type(new PubSubType());
    type.register_type(participant_);  // A second registration of the same type is a no-op.
    fdds::Topic* t =
        participant_->create_topic("rt" + ros_topic, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    topics_[ros_topic] = t;
    return t;
  }

  fdds::DomainParticipant* participant_ = nullptr;
  fdds::Publisher* publisher_ = nullptr;
  fdds::Subscriber* subscriber_ = nullptr;
  std::map<std::string, fdds::Topic*> topics_;
};

int matched(fdds::DataWriter* w) {
  fdds::PublicationMatchedStatus s;
  w->get_publication_matched_status(s);
  return s.current_count;
}
int matched(fdds::DataReader* r) {
  fdds::SubscriptionMatchedStatus s;
  r->get_subscription_matched_status(s);
  return s.current_count;
}

// The samples @p reader has, after waiting up to @p wait_s for the first.
template <class T>
std::vector<T> take(fdds::DataReader* reader, double wait_s) {
  if (wait_s > 0.0) {
    const auto ms = static_cast<std::uint32_t>(wait_s * 1000.0);
    reader->wait_for_unread_message(eprosima::fastrtps::Duration_t(
        static_cast<std::int32_t>(ms / 1000), (ms % 1000) * 1000000));
  }
  std::vector<T> out;
  T sample;
  fdds::SampleInfo info;
  while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
    if (info.valid_data) out.push_back(sample);
  }
  return out;
}

FastScan to_fastdds(const io::ScanMessage& m) {
  FastScan s;
  s.header_().stamp_().sec_(static_cast<std::int32_t>(m.header.stamp.sec));
  s.header_().stamp_().nanosec_(m.header.stamp.nsec);
  s.header_().frame_id_(m.header.frame_id);
  s.angle_min_(static_cast<float>(m.scan.angle_min_rad));
  s.angle_max_(m.angle_max);
  s.angle_increment_(static_cast<float>(m.scan.angle_increment_rad));
  s.time_increment_(m.time_increment);
  s.scan_time_(m.scan_time);
  s.range_min_(m.scan.range_min_m);
  s.range_max_(m.scan.range_max_m);
  s.ranges_(m.scan.ranges_m);
  s.intensities_(m.scan.intensities);
  return s;
}

// One transform, planar: @p pose of @p child in @p parent.
FastTf transform(const io::Stamp& stamp, const std::string& parent, const std::string& child,
                 const Pose2& pose) {
  geometry_msgs::msg::dds_::TransformStamped_ t;
  t.header_().stamp_().sec_(static_cast<std::int32_t>(stamp.sec));
  t.header_().stamp_().nanosec_(stamp.nsec);
  t.header_().frame_id_(parent);
  t.child_frame_id_(child);
  t.transform_member_().translation_().x_(pose.x_m);
  t.transform_member_().translation_().y_(pose.y_m);
  t.transform_member_().rotation_().z_(std::sin(0.5 * pose.yaw_rad));
  t.transform_member_().rotation_().w_(std::cos(0.5 * pose.yaw_rad));
  FastTf message;
  message.transforms_().push_back(t);
  return message;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

// What Fast DDS read must be @p want, every field, the floats bit for bit (NaN included).
void expect_equal(const FastScan& got, const io::ScanMessage& want, const char* topic,
                  std::size_t k) {
  SCOPED_TRACE(std::string(topic) + ", scan " + std::to_string(k));
  const FastScan w = to_fastdds(want);
  EXPECT_EQ(got.header_().stamp_().sec_(), w.header_().stamp_().sec_());
  EXPECT_EQ(got.header_().stamp_().nanosec_(), w.header_().stamp_().nanosec_());
  EXPECT_EQ(got.header_().frame_id_(), w.header_().frame_id_());
  const std::vector<float> got_fields = {
      got.angle_min_(), got.angle_max_(), got.angle_increment_(), got.time_increment_(),
      got.scan_time_(), got.range_min_(), got.range_max_()};
  const std::vector<float> want_fields = {w.angle_min_(),      w.angle_max_(), w.angle_increment_(),
                                          w.time_increment_(), w.scan_time_(), w.range_min_(),
                                          w.range_max_()};
  EXPECT_TRUE(same_bits(got_fields, want_fields));
  EXPECT_TRUE(same_bits(got.ranges_(), w.ranges_()));
  EXPECT_TRUE(same_bits(got.intensities_(), w.intensities_()));
}

// The leg_tracker recording's scans (a Hokuyo standing still, people walking past), the first
// @p at_most of them.
std::vector<io::ScanMessage> leg_tracker_scans(std::size_t at_most = 100000) {
  auto reader = jobs::open_recording(
      test::source_path("data/leg_tracker/demo_stationary_simple_environment.bag"));
  std::vector<io::ScanMessage> scans;
  reader->read({"/scan"}, [&](const io::RecordedMessage& m) {
    if (auto s = m.scan(); s && scans.size() < at_most) scans.push_back(*s);
  });
  return scans;
}

// The node (Cyclone) and a ROS 2 process on Fast DDS that drives it and subscribes to it, once
// every end of every topic has found its other end.
class CrossVendorSession {
 public:
  CrossVendorSession(const std::string& tag, const std::string& parameters)
      : scan_topic_("/scan_" + tag + std::to_string(::getpid())),
        node_name_("dispel_filter_" + tag + std::to_string(::getpid())),
        node_("filter",
              parameters + "    scan_topic: " + scan_topic_ + "\n    diagnostics_period_s: 0.1\n",
              node_name_, domain()),
        driver_(domain()) {}

  static int domain() {
    ::setenv("CYCLONEDDS_URI", kLoopback, 1);  // The node's DDS, on the loopback as this side.
    // Domains 10-49, as the other live tests: topics and node names are this process's own.
    return 10 + static_cast<int>(::getpid() % 40);
  }

  /// Creates the driver's writers and the subscriber's readers and waits for the node to match
  /// them (fatal failures: call under ASSERT_NO_FATAL_FAILURE).
  void start(const RosQos& scan_qos) {
    ASSERT_TRUE(driver_.ok());
    using ScanType = sensor_msgs::msg::dds_::LaserScan_PubSubType;
    using TfType = tf2_msgs::msg::dds_::TFMessage_PubSubType;
    tf_static_ = driver_.writer<TfType>("/tf_static", kTfStatic);
    tf_ = driver_.writer<TfType>("/tf", kTf);
    scans_ = driver_.writer<ScanType>(scan_topic_, scan_qos);
    filtered_ = driver_.reader<ScanType>(scan_topic_ + "_filtered", kSensorData);  // SLAM Toolbox
    labels_ = driver_.reader<ScanType>(scan_topic_ + "_labels", kDefaults);
    // As ROS 2's diagnostic_aggregator subscribes.
    diagnostics_ = driver_.reader<diagnostic_msgs::msg::dds_::DiagnosticArray_PubSubType>(
        "/diagnostics", kDefaults);
    ASSERT_TRUE(tf_static_ && tf_ && scans_ && filtered_ && labels_ && diagnostics_);
    ASSERT_TRUE(eventually([&] {
      const std::string log = node_.log();
      return matched(scans_) == 1 && matched(filtered_) == 1 && matched(labels_) == 1 &&
             matched(tf_) >= 1 && matched(tf_static_) >= 1 && matched(diagnostics_) >= 1 &&
             log.find(scan_topic_ + ": 1 publishers matched") != std::string::npos &&
             log.find(scan_topic_ + "_filtered: 1 subscribers matched") != std::string::npos &&
             log.find(scan_topic_ + "_labels: 1 subscribers matched") != std::string::npos;
    })) << node_.log();
  }

  void tf_static(const io::FrameTransform& t) { write(tf_static_, t); }
  void tf(const io::FrameTransform& t) { write(tf_, t); }

  /// Sends @p scan, then takes the node's filtered scan and labels for it, and checks they are
  /// @p want's (fatal failures).
  void exchange(const io::ScanMessage& scan, const io::ScanMessage& want_filtered,
                const io::ScanMessage& want_labels, std::size_t k) {
    FastScan f, l;
    ASSERT_NO_FATAL_FAILURE(send(scan, k, f, l));
    expect_equal(f, want_filtered, "filtered", k);
    expect_equal(l, want_labels, "labels", k);
    ASSERT_FALSE(::testing::Test::HasFailure());
  }

  /// Writes @p scan and does not wait.
  void write(const io::ScanMessage& scan) {
    FastScan sample = to_fastdds(scan);
    ASSERT_TRUE(scans_->write(&sample));
  }
  /// The label scans that came within @p wait_s of each other.
  std::vector<FastScan> take_labels(double wait_s) {
    std::vector<FastScan> out;
    for (std::vector<FastScan> got = take<FastScan>(labels_, wait_s); !got.empty();
         got = take<FastScan>(labels_, wait_s)) {
      out.insert(out.end(), got.begin(), got.end());
    }
    return out;
  }

  /// Sends @p scan (the @p k th), then takes the node's filtered scan and labels for it.
  void send(const io::ScanMessage& scan, std::size_t k, FastScan& filtered, FastScan& labels) {
    FastScan sample = to_fastdds(scan);
    ASSERT_TRUE(scans_->write(&sample));
    std::vector<FastScan> f, l;
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(2.0 * kWaitS);
    while ((f.empty() || l.empty()) && std::chrono::steady_clock::now() < deadline) {
      for (auto& s : take<FastScan>(filtered_, f.empty() ? 0.05 : 0.0)) f.push_back(std::move(s));
      for (auto& s : take<FastScan>(labels_, l.empty() ? 0.05 : 0.0)) l.push_back(std::move(s));
    }
    ASSERT_TRUE(!f.empty() && !l.empty()) << "scan " << k << "\n" << node_.log();
    ASSERT_EQ(f.size(), 1u) << k;
    ASSERT_EQ(l.size(), 1u) << k;
    filtered = f[0];
    labels = l[0];
  }

  /// The driver's scan publisher goes away (a driver that stopped): the node says so.
  void scan_publisher_vanishes() {
    driver_.remove(scans_);
    scans_ = nullptr;
    ASSERT_TRUE(eventually([&] {
      return node_.log().find(scan_topic_ + ": 0 publishers matched") != std::string::npos;
    })) << node_.log();
  }
  /// A new one comes (the driver started again): the node matches it.
  void scan_publisher_returns(const RosQos& qos) {
    scans_ = driver_.writer<sensor_msgs::msg::dds_::LaserScan_PubSubType>(scan_topic_, qos);
    ASSERT_NE(scans_, nullptr);
    const std::string matched_line = scan_topic_ + ": 1 publishers matched";
    ASSERT_TRUE(eventually([&] {
      const std::string log = node_.log();
      const std::size_t first = log.find(matched_line);
      return matched(scans_) == 1 && first != std::string::npos &&
             log.find(matched_line, first + 1) != std::string::npos;
    })) << node_.log();
  }

  /// A /clock publisher as `ros2 bag play --clock` makes one (best effort, keep last 1), once
  /// the node (use_sim_time) has matched it.
  void start_clock() {
    clock_ = driver_.writer<rosgraph_msgs::msg::dds_::Clock_PubSubType>("/clock", kClock);
    ASSERT_NE(clock_, nullptr);
    ASSERT_TRUE(eventually([&] {
      return matched(clock_) == 1 &&
             node_.log().find("/clock: 1 publishers matched") != std::string::npos;
    })) << node_.log();
  }
  void clock(const io::Stamp& t) {
    rosgraph_msgs::msg::dds_::Clock_ c;
    c.clock_().sec_(static_cast<std::int32_t>(t.sec));
    c.clock_().nanosec_(t.nsec);
    ASSERT_TRUE(clock_->write(&c));
  }

  using Status = diagnostic_msgs::msg::dds_::DiagnosticStatus_;
  static std::string value(const Status& s, const std::string& key) {
    for (const auto& kv : s.values_()) {
      if (kv.key_() == key) return kv.value_();
    }
    return "(no key " + key + ")";
  }
  /// Takes the node's statuses on /diagnostics, calling @p tick between looks, until one whose
  /// header stamp (whole seconds) and contents satisfy @p done; @p last is the last of this
  /// node's seen and @p stamp_s its stamp. False when none did within kWaitS.
  bool status_until(const std::function<bool(const Status&, std::int32_t)>& done,
                    const std::function<void()>& tick, Status& last, std::int32_t& stamp_s) {
    return eventually([&] {
      if (tick) tick();
      using Array = diagnostic_msgs::msg::dds_::DiagnosticArray_;
      for (const Array& a : take<Array>(diagnostics_, 0.0)) {
        for (const Status& s : a.status_()) {
          if (s.name_() != node_name_ + ": dynamic filter") continue;  // Another test's node.
          last = s;
          stamp_s = a.header_().stamp_().sec_();
          if (done(last, stamp_s)) return true;
        }
      }
      return false;
    });
  }

  /// The node's status on /diagnostics comes to say that @p scans came in, every one with its
  /// sensor pose, none dropped, nothing undecodable (the node publishes it every 0.1 s).
  void expect_diagnostics(std::size_t scans) {
    Status last;
    std::int32_t stamp_s = 0;
    const bool came = status_until(
        [&](const Status& s, std::int32_t) { return value(s, "scans") == std::to_string(scans); },
        {}, last, stamp_s);
    ASSERT_TRUE(came) << "last status: " << last.message_() << ", scans " << value(last, "scans");
    EXPECT_EQ(last.level_(), 0) << last.message_();  // OK
    EXPECT_GT(stamp_s, 1600000000);                  // ROS time: the system clock.
    EXPECT_EQ(value(last, "scans without a sensor pose"), "0");
    EXPECT_EQ(value(last, "scans dropped (queue full)"), "0");
    EXPECT_EQ(value(last, "undecodable messages"), "0");
    EXPECT_NE(value(last, "beams removed (dynamic)"), "0");
  }

  /// A subscriber asking for what the node's writers do not offer (transient local): the node
  /// says so in its log, and Fast DDS's side sees the same mismatch. Then SIGTERM: exit 0, with
  /// @p scans in and published.
  void mismatch_and_stop(std::size_t scans) { mismatch_and_stop(scans, scans); }
  /// The same with @p published of them published, stopped by @p signal.
  void mismatch_and_stop(std::size_t scans, std::size_t published, int signal = SIGTERM) {
    fdds::DataReader* latched = driver_.reader<sensor_msgs::msg::dds_::LaserScan_PubSubType>(
        scan_topic_ + "_filtered", kLatchedReader);
    ASSERT_NE(latched, nullptr);
    ASSERT_TRUE(eventually([&] {
      return node_.log().find("warning: a subscriber of " + scan_topic_ +
                              "_filtered has a QoS this node cannot match") != std::string::npos;
    })) << node_.log();
    ASSERT_TRUE(eventually([&] {
      fdds::RequestedIncompatibleQosStatus s;
      latched->get_requested_incompatible_qos_status(s);
      return s.total_count >= 1 && s.last_policy_id == fdds::DURABILITY_QOS_POLICY_ID;
    }));
    EXPECT_EQ(node_.stop(signal), 0) << node_.log();
    const std::string counts =
        std::to_string(scans) + " scans in, " + std::to_string(published) + " published";
    EXPECT_NE(node_.log().find(counts), std::string::npos) << node_.log();
  }

 private:
  static void write(fdds::DataWriter* w, const io::FrameTransform& t) {
    FastTf message = transform(t.stamp, t.parent, t.child, t.child_in_parent);
    ASSERT_TRUE(w->write(&message));
  }

  std::string scan_topic_;
  std::string node_name_;
  NodeProcess node_;
  FastDdsProcess driver_;
  fdds::DataWriter* tf_static_ = nullptr;
  fdds::DataWriter* tf_ = nullptr;
  fdds::DataWriter* scans_ = nullptr;
  fdds::DataReader* filtered_ = nullptr;
  fdds::DataReader* labels_ = nullptr;
  fdds::DataReader* diagnostics_ = nullptr;
  fdds::DataWriter* clock_ = nullptr;
};

std::int64_t removed_beams(const io::ScanMessage& filtered) {
  std::int64_t n = 0;
  for (float r : filtered.scan.ranges_m) n += std::isnan(r) ? 1 : 0;
  return n;
}

// The real recording: a scanner standing still, people walking past. The robot stands in odom
// at (1.25, -2), the laser 0.25 m ahead of base_link; the reference is the runner given the
// sensor pose those make, (1.5, -2, 0), exact in binary. The filter does not depend on where a
// still sensor stands, so this case checks the scans' way through both vendors; the moving
// robot below checks the transforms'.
void play_real_recording(const RosQos& scan_qos, const char* tag) {
  std::vector<io::ScanMessage> scans = leg_tracker_scans();
  ASSERT_GT(scans.size(), 100u);
  pipeline::ScanFilterRunnerOptions options;
  options.config = io::parse_filter_config("{}", "defaults");
  options.scale_to_scanner = true;
  pipeline::ScanFilterRunner reference(options);

  CrossVendorSession session(tag,
                             "/**:\n  ros__parameters:\n    scale_to_scanner: true\n"
                             "    transform_timeout_s: " +
                                 std::to_string(kWaitS) + "\n");
  ASSERT_NO_FATAL_FAILURE(session.start(scan_qos));
  const io::Stamp t0 = scans.front().header.stamp;
  session.tf_static({t0, "base_link", scans.front().header.frame_id, Pose2{0.25, 0.0, 0.0}});
  std::int64_t removed = 0;
  for (std::size_t k = 0; k < scans.size(); ++k) {
    session.tf({scans[k].header.stamp, "odom", "base_link", Pose2{1.25, -2.0, 0.0}});
    const FilterResult& expected =
        reference.process(scans[k].scan, scans[k].scan_time, Pose2{1.5, -2.0, 0.0});
    const io::ScanMessage want = io::filtered_message(scans[k], expected);
    ASSERT_NO_FATAL_FAILURE(
        session.exchange(scans[k], want, io::labels_message(scans[k], expected), k));
    removed += removed_beams(want);
  }
  EXPECT_GT(removed, 0);  // The walkers: the comparison saw removals, not only a copy.
  session.expect_diagnostics(scans.size());
  session.mismatch_and_stop(scans.size());
}

TEST(Ros2FastDdsLive, ARealRecordingFromAFastDdsDriverWithReliableScans) {
  play_real_recording(kDefaults, "fr");
}

TEST(Ros2FastDdsLive, ARealRecordingFromAFastDdsDriverWithBestEffortScans) {
  play_real_recording(kSensorData, "fb");
}

// A robot driving: the simulator's busy corridor (people walking, the robot at walking speed),
// 10 s. `dispel filter` filters the recording (its /odom gives the poses); the driver plays the
// same recording as a ROS 2 robot's drivers do, the mount on /tf_static and each odometry
// message as the transform odom -> base_link on /tf, a scan once the transform at or after its
// stamp is out (what the node waits for). The node's poses come from /tf alone; its output must
// be what `dispel filter` wrote, scan for scan.
TEST(Ros2FastDdsLive, AMovingRobotFromAFastDdsDriverAsDispelFilterFiltersIt) {
  const std::string recording = test::temp_path("fastdds_moving.bag");
  const std::string filtered = test::temp_path("fastdds_moving_filtered.bag");
  jobs::simulate_to_recording(
      io::load_scenario(test::source_path("config/scenarios/busy_corridor.yaml")), 1, 10.0,
      recording);
  jobs::FilterJobOptions job;
  job.input = recording;
  job.output = filtered;
  const jobs::FilterJobStats stats = jobs::run_filter_job(job);
  ASSERT_GT(stats.scans_filtered, 150);

  std::vector<io::ScanMessage> want_filtered, want_labels;
  jobs::open_recording(filtered)->read(
      {"/scan_filtered", "/scan_labels"}, [&](const io::RecordedMessage& m) {
        (m.topic() == "/scan_filtered" ? want_filtered : want_labels).push_back(*m.scan());
      });
  ASSERT_EQ(want_filtered.size(), static_cast<std::size_t>(stats.scans));
  ASSERT_EQ(want_labels.size(), want_filtered.size());

  CrossVendorSession session(
      "fm", "/**:\n  ros__parameters:\n    transform_timeout_s: " + std::to_string(kWaitS) + "\n");
  ASSERT_NO_FATAL_FAILURE(session.start(kSensorData));
  std::vector<io::ScanMessage> pending;  // Scans whose transform is not out yet.
  std::size_t sent = 0;
  std::int64_t removed = 0;
  const auto send_pending = [&](const io::Stamp& odom_stamp) {
    while (!pending.empty() && !(odom_stamp < pending.front().header.stamp)) {
      ASSERT_NO_FATAL_FAILURE(
          session.exchange(pending.front(), want_filtered[sent], want_labels[sent], sent));
      removed += removed_beams(want_filtered[sent]);
      ++sent;
      pending.erase(pending.begin());
    }
  };
  jobs::open_recording(recording)->read(
      {"/tf_static", "/odom", "/scan"}, [&](const io::RecordedMessage& m) {
        if (::testing::Test::HasFatalFailure()) return;
        if (auto t = m.transforms()) {
          for (const io::FrameTransform& f : t->transforms) session.tf_static(f);
        } else if (auto o = m.odometry()) {
          session.tf({o->header.stamp, o->header.frame_id, o->child_frame_id, o->pose});
          send_pending(o->header.stamp);
        } else if (auto s = m.scan()) {
          pending.push_back(*s);
        }
      });
  ASSERT_FALSE(::testing::Test::HasFatalFailure());
  // Scans after the last odometry message never get a pose from /tf: not played.
  EXPECT_LE(pending.size(), 1u);
  EXPECT_GT(sent, 150u);
  EXPECT_GT(removed, 0);
  session.expect_diagnostics(sent);
  session.mismatch_and_stop(sent);
}

// use_sim_time across vendors: ROS time is what a Fast DDS /clock publisher says, as under
// `ros2 bag play --clock`. The scans come without stamps (a driver without a clock): the node
// filters each at the ROS time it came and publishes it with its zero stamp kept; its
// /diagnostics are stamped with /clock's time. Then the clock goes back, as when a replay starts
// again, and the node's time follows it. (Which /clock sample a scan meets is the wire's to
// decide, so the scans' filtering is not compared here; the moving robot above compares it.)
TEST(Ros2FastDdsLive, UseSimTimeTakesRosTimeFromAFastDdsClockThroughAReset) {
  std::vector<io::ScanMessage> scans = leg_tracker_scans(40);
  ASSERT_EQ(scans.size(), 40u);
  for (io::ScanMessage& s : scans) s.header.stamp = io::Stamp{};  // No clock on the driver.

  CrossVendorSession session("fc",
                             "/**:\n  ros__parameters:\n    static_sensor: true\n"
                             "    use_sim_time: true\n");
  ASSERT_NO_FATAL_FAILURE(session.start(kSensorData));
  ASSERT_NO_FATAL_FAILURE(session.start_clock());
  // Two runs of the recording's clock: from 5000 s, then from 100 s (the replay again).
  std::size_t sent = 0;
  for (const std::int64_t start_s : {5000, 100}) {
    SCOPED_TRACE("clock from " + std::to_string(start_s) + " s");
    io::Stamp now{start_s, 0};
    const auto tick = [&] {
      now = io::Stamp::from_seconds(now.seconds() + 0.01);
      session.clock(now);
    };
    for (int k = 0; k < 20; ++k, ++sent) {
      tick();
      FastScan f, l;
      ASSERT_NO_FATAL_FAILURE(session.send(scans[sent], sent, f, l));
      EXPECT_EQ(f.header_().stamp_().sec_(), 0);  // Published as it came.
      EXPECT_EQ(f.header_().stamp_().nanosec_(), 0u);
      EXPECT_EQ(f.ranges_().size(), scans[sent].scan.ranges_m.size());
    }
    CrossVendorSession::Status last;
    std::int32_t stamp_s = 0;
    const std::string all = std::to_string(sent);
    ASSERT_TRUE(session.status_until(
        [&](const CrossVendorSession::Status& s, std::int32_t t) {
          return t >= start_s && t < start_s + 60 &&
                 CrossVendorSession::value(s, "scans without a stamp") == all;
        },
        tick, last, stamp_s))
        << "last status at " << stamp_s
        << " s: " << CrossVendorSession::value(last, "scans without a stamp")
        << " scans without a stamp";
  }
  session.mismatch_and_stop(sent);
}

// A flood: a driver writes the recording's 1265 scans as fast as it can (their stamps 1 ms
// apart), while no transform gives them a pose, so every scan the node takes has to wait. The
// node keeps at most queue_size (3) of them: it drops the oldest and counts them, and its
// memory for waiting scans stays bounded, however many come. (How many the node takes is DDS's
// and the scheduler's to decide: its reader is best effort, keep last 5, as a driver's sensor
// data is read. What must hold is the bound and the count.) Then the transforms come, and the
// three waiting scans are filtered and published.
TEST(Ros2FastDdsLive, AFloodOfScansWithoutPosesIsDroppedAndCountedNotQueued) {
  std::vector<io::ScanMessage> scans = leg_tracker_scans();
  ASSERT_GT(scans.size(), 1000u);
  const double t0 = scans.front().header.stamp.seconds();
  for (std::size_t k = 0; k < scans.size(); ++k) {
    scans[k].header.stamp = io::Stamp::from_seconds(t0 + 0.001 * static_cast<double>(k));
    scans[k].scan.stamp_s = scans[k].header.stamp.seconds();
  }
  const double t_end = scans.back().header.stamp.seconds();

  // At least the 5 scans the node's reader keeps reach the node, however loaded the machine.
  constexpr int kQueue = 3;
  CrossVendorSession session("ff",
                             "/**:\n  ros__parameters:\n    queue_size: " + std::to_string(kQueue) +
                                 "\n    transform_timeout_s: 1000.0\n");
  ASSERT_NO_FATAL_FAILURE(session.start(kSensorData));
  const std::string laser = scans.front().header.frame_id;
  session.tf_static({scans.front().header.stamp, "base_link", laser, Pose2{}});
  for (const io::ScanMessage& s : scans) ASSERT_NO_FATAL_FAILURE(session.write(s));

  // The flood is over once the node's count has not grown for 1 s (ten statuses): every write
  // returned long before, and what is on the loopback reaches the node within milliseconds.
  CrossVendorSession::Status last;
  std::int32_t stamp_s = 0;
  std::string received_before;
  auto unchanged_since = std::chrono::steady_clock::now();
  ASSERT_TRUE(session.status_until(
      [&](const CrossVendorSession::Status& s, std::int32_t) {
        const std::string received = CrossVendorSession::value(s, "scans received");
        if (received != received_before) {
          received_before = received;
          unchanged_since = std::chrono::steady_clock::now();
        }
        return std::stoll(received) > kQueue &&
               std::chrono::steady_clock::now() - unchanged_since > std::chrono::seconds(1);
      },
      {}, last, stamp_s))
      << CrossVendorSession::value(last, "scans received") << " scans received";
  const long long received = std::stoll(CrossVendorSession::value(last, "scans received"));
  std::printf("flood: %lld of %zu scans reached the node\n", received, scans.size());
  EXPECT_EQ(CrossVendorSession::value(last, "scans waiting for a sensor pose"),
            std::to_string(kQueue));
  EXPECT_EQ(CrossVendorSession::value(last, "scans dropped (queue full)"),
            std::to_string(received - kQueue));
  EXPECT_EQ(CrossVendorSession::value(last, "scans"), "0");  // None filtered yet.

  // The robot's motion over the flood's stamps, every 0.25 s: the ten get their poses.
  for (double t = t0 - 0.25; t < t_end + 0.5; t += 0.25) {
    session.tf({io::Stamp::from_seconds(t), "odom", "base_link", Pose2{}});
  }
  std::vector<FastScan> labels;
  ASSERT_TRUE(eventually([&] {
    for (FastScan& l : session.take_labels(0.05)) labels.push_back(std::move(l));
    return labels.size() >= static_cast<std::size_t>(kQueue);
  }));
  ASSERT_EQ(labels.size(), static_cast<std::size_t>(kQueue));
  // The newest the node took, in order.
  for (std::size_t k = 1; k < labels.size(); ++k) {
    const auto stamp = [](const FastScan& s) {
      return io::Stamp{s.header_().stamp_().sec_(), s.header_().stamp_().nanosec_()};
    };
    EXPECT_TRUE(stamp(labels[k - 1]) < stamp(labels[k])) << k;
  }
  ASSERT_TRUE(session.status_until(
      [&](const CrossVendorSession::Status& s, std::int32_t) {
        return CrossVendorSession::value(s, "scans") == std::to_string(kQueue) &&
               CrossVendorSession::value(s, "scans waiting for a sensor pose") == "0";
      },
      {}, last, stamp_s));
  EXPECT_EQ(CrossVendorSession::value(last, "scans received"), std::to_string(received));
  EXPECT_EQ(CrossVendorSession::value(last, "scans dropped (queue full)"),
            std::to_string(received - kQueue));
  session.mismatch_and_stop(static_cast<std::size_t>(received), kQueue);
}

// No publisher, then one that vanishes and comes back: the node waits without one (its
// /diagnostics say "no scans"), filters what the driver sends, says when the driver is gone and
// when it is back, and goes on; Ctrl-C (SIGINT) stops it with its counts.
TEST(Ros2FastDdsLive, NoPublisherThenOneThatVanishesAndComesBackThenCtrlC) {
  const std::vector<io::ScanMessage> scans = leg_tracker_scans(20);
  ASSERT_EQ(scans.size(), 20u);
  CrossVendorSession session("fv", "/**:\n  ros__parameters:\n    static_sensor: true\n");
  ASSERT_NO_FATAL_FAILURE(session.start(kSensorData));
  CrossVendorSession::Status last;
  std::int32_t stamp_s = 0;
  ASSERT_TRUE(session.status_until(
      [](const CrossVendorSession::Status& s, std::int32_t) {
        return s.message_() == "no scans" && s.level_() == 0;
      },
      {}, last, stamp_s))
      << last.message_();
  std::size_t sent = 0;
  for (int run = 0; run < 2; ++run) {
    if (run == 1) {
      ASSERT_NO_FATAL_FAILURE(session.scan_publisher_vanishes());
      ASSERT_NO_FATAL_FAILURE(session.scan_publisher_returns(kDefaults));
    }
    for (int k = 0; k < 10; ++k, ++sent) {
      FastScan f, l;
      ASSERT_NO_FATAL_FAILURE(session.send(scans[sent], sent, f, l));
      EXPECT_EQ(f.header_().stamp_().sec_(), scans[sent].header.stamp.sec);
    }
  }
  session.mismatch_and_stop(sent, sent, SIGINT);
}

}  // namespace
}  // namespace dispel::ros2
