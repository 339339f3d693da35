// dispel-ros2: dispel's nodes on ROS 2, as DDS participants that follow ROS 2's mapping onto DDS
// (Cyclone DDS; docs/ros2.md). No ROS 2 install is needed, on this machine or the robot's.
//
//   dispel-ros2 filter|odometry [--params-file FILE] [--node-name NAME]
//   dispel-ros2 filter|odometry --ros-args [--params-file FILE]... [-p NAME:=VALUE]...
//                                          [-r __node:=NAME] [-r __ns:=/]   (as ros2 launch runs
//                                          it)
//
// filter: subscribes <scan_topic> (sensor_msgs/LaserScan, best effort: any driver's QoS), /tf
// and /tf_static; publishes <scan_topic>_filtered (removed beams NaN) and <scan_topic>_labels
// (intensities = beam labels), reliable. odometry: subscribes <wheels_topic> (JointState or
// Odometry) and <imu_topic> (Imu); publishes <odometry_topic> (nav_msgs/Odometry) and, with
// publish_tf, /tf. Both publish /diagnostics every diagnostics_period_s. The work is
// FilterNodeCore's and OdometryNodeCore's; this file is the middleware around them. Ctrl-C or
// SIGTERM stops a node after the message in hand; it then prints its counts. Exit status: 0, 2 for
// a bad command line or parameter file, 3 for a DDS failure.
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "dispel/io/errors.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "dispel/io/text.hpp"
#include "dispel/pipeline/resident_heap.hpp"
#include "dispel/ros2/dds.hpp"
#include "dispel/ros2/filter_node.hpp"
#include "dispel/ros2/graph.hpp"
#include "dispel/ros2/odometry_node.hpp"

namespace {

using namespace dispel;

std::atomic<bool> g_stop{false};

void on_signal(int) { g_stop = true; }

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

int usage(const std::string& problem) {
  std::fprintf(stderr,
               "dispel-ros2: %s\nusage: dispel-ros2 filter|odometry [--params-file FILE]... "
               "[--node-name NAME]\n       dispel-ros2 filter|odometry --ros-args [--params-file "
               "FILE]... [-p NAME:=VALUE]... [-r __node:=NAME] [-r __ns:=/]\n",
               problem.c_str());
  return 2;
}

// What both nodes do around their work: the participant, ROS time (the system clock, or /clock
// under use_sim_time), the node in ROS 2's graph, the signals, and the connections said as they
// change (a driver found, SLAM subscribed) with a QoS that keeps another node's endpoint out said
// once per endpoint (DDS counts them), not left silent.
class NodeRuntime {
 public:
  NodeRuntime(const char* command, std::string node_name, bool use_sim_time,
              const std::string& ros_distro)
      : command_(command),
        node_name_(std::move(node_name)),
        participant_(ros2::domain_from_environment()) {
    if (use_sim_time) {  // ROS 2's clock QoS: best effort, keep last 1.
      clock_.emplace(
          participant_, "/clock", "rosgraph_msgs/msg/Clock",
          ros2::Qos{ros2::Qos::Reliability::kBestEffort, ros2::Qos::Durability::kVolatile, 1});
      watch(*clock_, "/clock");
    }
    distro_ = ros_distro;  // Checked when the parameters were read.
    if (distro_.empty()) {
      const char* env = std::getenv("ROS_DISTRO");
      distro_ = env != nullptr && *env != '\0' ? env : "humble";
      try {
        ros2::gid_layout_named(distro_);
      } catch (const ros2::DdsError&) {  // A ROS 1 shell's "noetic", say.
        std::fprintf(stderr,
                     "dispel-ros2 %s: warning: ROS_DISTRO=%s is not a ROS 2 distribution this "
                     "node knows; its graph uses humble's layout (set ros_distro to choose)\n",
                     command_, io::one_line(distro_, 40).c_str());
        distro_ = "humble";
      }
    }
    struct sigaction action {};
    action.sa_handler = on_signal;
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
  }

  ros2::Participant& participant() { return participant_; }
  const char* command() const { return command_; }

  /// Said when connections change; @p topic names it.
  void watch(const ros2::Reader& r, const std::string& topic) {
    watched_.push_back({&r, nullptr, topic});
  }
  void watch(const ros2::Writer& w, const std::string& topic) {
    watched_.push_back({nullptr, &w, topic});
  }

  /// Publishes the node in ROS 2's graph, with the endpoints watched as its own.
  void join_graph() {
    ros2::NodeEntities node{"/", node_name_, {}, {}};
    for (const Watched& w : watched_) {
      if (w.reader != nullptr) node.readers.push_back(w.reader->guid());
      if (w.writer != nullptr) node.writers.push_back(w.writer->guid());
    }
    graph_.emplace(participant_, ros2::discovery_topic(), ros2::discovery_qos());
    graph_->write(ros2::encode_participant_entities(participant_.guid(), {node},
                                                    ros2::gid_layout_named(distro_)));
    std::fprintf(stderr, "dispel-ros2 %s: node /%s on domain %d (graph in %s's layout)\n", command_,
                 node_name_.c_str(), participant_.domain_id(), distro_.c_str());
  }

  /// ROS time now.
  io::Stamp ros_time() {
    if (!clock_)
      return io::Stamp::from_seconds(
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
              .count());
    for (const auto& bytes : clock_->take(0.0)) {
      try {
        sim_time_s_ = io::decode_ros2_clock(bytes.data(), bytes.size()).seconds();
      } catch (const io::CdrError&) {
        ++undecodable_;
      }
    }
    return io::Stamp::from_seconds(sim_time_s_);
  }

  /// Says what changed in the connections, at most every 0.5 s.
  void report(double now_s) {
    if (now_s < next_report_s_) return;
    next_report_s_ = now_s + 0.5;
    for (Watched& w : watched_) {
      const ros2::Matches m = w.reader != nullptr ? w.reader->matches() : w.writer->matches();
      const char* ends = w.reader != nullptr ? "publishers" : "subscribers";
      if (m.current != w.connected) {
        w.connected = m.current;
        std::fprintf(stderr, "dispel-ros2 %s: %s: %d %s matched\n", command_, w.topic.c_str(),
                     m.current, ends);
      }
      if (m.incompatible <= w.reported) continue;
      w.reported = m.incompatible;
      std::fprintf(stderr,
                   "dispel-ros2 %s: warning: a %s of %s has a QoS this node cannot match (%s); "
                   "it is not connected\n",
                   command_, w.reader != nullptr ? "publisher" : "subscriber", w.topic.c_str(),
                   m.last_incompatible_policy.c_str());
    }
  }

  std::int64_t undecodable() const { return undecodable_; }
  void count_undecodable() { ++undecodable_; }

  /// Publishes on /diagnostics (diagnostic_updater's QoS: reliable, volatile) every @p period_s
  /// of steady time; call join_graph() after it.
  void publish_diagnostics_every(double period_s) {
    diagnostics_.emplace(participant_, "/diagnostics", "diagnostic_msgs/msg/DiagnosticArray",
                         ros2::Qos::defaults());
    watch(*diagnostics_, "/diagnostics");
    diagnostics_period_s_ = period_s;
  }
  /// Whether a status is due at @p now_s (the first one a period after the first call).
  bool diagnostics_due(double now_s) {
    if (next_diagnostics_s_ == 0.0) next_diagnostics_s_ = now_s + diagnostics_period_s_;
    if (now_s < next_diagnostics_s_) return false;
    next_diagnostics_s_ = std::max(next_diagnostics_s_ + diagnostics_period_s_, now_s);
    return true;
  }
  void publish_diagnostics(const pipeline::DiagnosticStatus& status) {
    diagnostics_->write(io::encode_ros2_diagnostics(ros_time(), {status}));
  }

 private:
  struct Watched {
    const ros2::Reader* reader;
    const ros2::Writer* writer;
    std::string topic;
    int reported = 0;
    int connected = 0;
  };
  const char* command_;
  std::string node_name_;
  ros2::Participant participant_;
  std::optional<ros2::Reader> clock_;
  double sim_time_s_ = 0.0;
  std::string distro_;
  std::optional<ros2::Writer> graph_;
  std::optional<ros2::Writer> diagnostics_;
  double diagnostics_period_s_ = 1.0;
  double next_diagnostics_s_ = 0.0;
  std::vector<Watched> watched_;
  double next_report_s_ = 0.0;
  std::int64_t undecodable_ = 0;
};

// Decodes @p bytes with @p decode; counts and skips what does not decode.
template <typename Decode>
auto decoded(NodeRuntime& rt, const std::vector<std::uint8_t>& bytes, Decode decode)
    -> std::optional<decltype(decode(bytes.data(), bytes.size()))> {
  try {
    return decode(bytes.data(), bytes.size());
  } catch (const io::CdrError&) {
    rt.count_undecodable();
    return std::nullopt;
  }
}

// A loop iteration waits this long for its main input; a message wakes it at once.
constexpr double kLoopWaitS = 0.02;

int run_filter(const ros2::FilterNodeSettings& settings) {
  NodeRuntime rt("filter", settings.node_name, settings.use_sim_time, settings.ros_distro);
  ros2::Participant& p = rt.participant();
  const std::string scan_type = "sensor_msgs/msg/LaserScan";
  const std::string tf_type = "tf2_msgs/msg/TFMessage";
  const std::string filtered_topic = settings.scan_topic + "_filtered";
  const std::string labels_topic = settings.scan_topic + "_labels";
  // A best-effort reader matches best-effort and reliable drivers alike.
  ros2::Reader scans(p, settings.scan_topic, scan_type, ros2::Qos::sensor_data());
  ros2::Reader tf(p, "/tf", tf_type,
                  {ros2::Qos::Reliability::kReliable, ros2::Qos::Durability::kVolatile, 100});
  ros2::Reader tf_static(p, "/tf_static", tf_type, ros2::Qos::tf_static_subscriber());
  ros2::Writer filtered(p, filtered_topic, scan_type, ros2::Qos::defaults());
  ros2::Writer labels(p, labels_topic, scan_type, ros2::Qos::defaults());
  rt.watch(scans, settings.scan_topic);
  rt.watch(tf, "/tf");
  rt.watch(tf_static, "/tf_static");
  rt.watch(filtered, filtered_topic);
  rt.watch(labels, labels_topic);
  rt.publish_diagnostics_every(settings.diagnostics_period_s);
  rt.join_graph();
  std::fprintf(stderr, "dispel-ros2 filter: %s -> %s, %s\n", settings.scan_topic.c_str(),
               filtered_topic.c_str(), labels_topic.c_str());
  ros2::FilterNodeCore core(settings);

  const auto take_transforms = [&](ros2::Reader& reader, bool is_static) {
    for (const auto& bytes : reader.take(0.0)) {
      if (auto m = decoded(rt, bytes, io::decode_ros2_transforms)) core.transforms(*m, is_static);
    }
  };
  const auto publish = [&](const std::vector<ros2::FilterNodeOutput>& outputs) {
    for (const ros2::FilterNodeOutput& o : outputs) {
      filtered.write(io::encode_ros2(o.filtered));
      labels.write(io::encode_ros2(o.labels));
    }
  };
  // Transforms are taken before each scan; a scan waiting for its pose is looked at again
  // within the loop's wait.
  while (!g_stop) {
    take_transforms(tf_static, true);
    take_transforms(tf, false);
    for (const auto& bytes : scans.take(kLoopWaitS)) {
      take_transforms(tf_static, true);
      take_transforms(tf, false);
      if (auto m = decoded(rt, bytes, io::decode_ros2_scan)) {
        publish(core.scan(std::move(*m), steady_seconds(), rt.ros_time().seconds()));
      }
    }
    const double now_s = steady_seconds();
    publish(core.poll(now_s));
    rt.report(now_s);
    if (rt.diagnostics_due(now_s)) rt.publish_diagnostics(core.diagnostics(rt.undecodable()));
  }
  const ros2::FilterNodeCounts& c = core.counts();
  const pipeline::ScanFilterCounts& r = core.runner().counts();
  std::fprintf(stderr,
               "dispel-ros2 filter: %lld scans in, %lld published (%lld filtered, %lld without "
               "a pose), %lld dropped without a transform, %lld dropped from a full queue, %lld "
               "undecodable messages, %lld transforms refused, %lld times time went backwards, "
               "%lld scans without a stamp\n",
               static_cast<long long>(c.scans_in), static_cast<long long>(c.published),
               static_cast<long long>(r.filtered), static_cast<long long>(r.no_pose),
               static_cast<long long>(c.dropped_without_transform),
               static_cast<long long>(c.dropped_queue_full),
               static_cast<long long>(rt.undecodable() + c.undecodable),
               static_cast<long long>(c.transforms_refused), static_cast<long long>(c.time_resets),
               static_cast<long long>(c.zero_stamps));
  return 0;
}

int run_odometry(const ros2::OdometryNodeSettings& settings) {
  NodeRuntime rt("odometry", settings.node_name, settings.use_sim_time, settings.ros_distro);
  ros2::Participant& p = rt.participant();
  // Best effort in: it matches any driver. Kept: queue_size (an IMU at 200 Hz fills ROS 2's
  // sensor-data depth of 5 within one wait of the loop).
  const ros2::Qos in{ros2::Qos::Reliability::kBestEffort, ros2::Qos::Durability::kVolatile,
                     settings.queue_size};
  ros2::Reader wheels(
      p, settings.wheels_topic,
      settings.wheels_as_odometry ? "nav_msgs/msg/Odometry" : "sensor_msgs/msg/JointState", in);
  ros2::Reader imu(p, settings.imu_topic, "sensor_msgs/msg/Imu", in);
  ros2::Writer odometry(
      p, settings.odometry_topic, "nav_msgs/msg/Odometry",
      {ros2::Qos::Reliability::kReliable, ros2::Qos::Durability::kVolatile, settings.queue_size});
  std::optional<ros2::Writer> tf;
  if (settings.publish_tf) {
    tf.emplace(p, "/tf", "tf2_msgs/msg/TFMessage",
               ros2::Qos{ros2::Qos::Reliability::kReliable, ros2::Qos::Durability::kVolatile, 100});
  }
  rt.watch(wheels, settings.wheels_topic);
  rt.watch(imu, settings.imu_topic);
  rt.watch(odometry, settings.odometry_topic);
  if (tf) rt.watch(*tf, "/tf");
  rt.publish_diagnostics_every(settings.diagnostics_period_s);
  rt.join_graph();
  std::fprintf(stderr, "dispel-ros2 odometry: %s (%s) + %s -> %s%s\n",
               settings.wheels_topic.c_str(),
               settings.wheels_as_odometry ? "nav_msgs/Odometry" : "sensor_msgs/JointState",
               settings.imu_topic.c_str(), settings.odometry_topic.c_str(),
               tf ? (", /tf " + settings.odom_frame + " -> " + settings.base_frame).c_str() : "");
  ros2::OdometryNodeCore core(settings);

  const auto publish = [&](const std::vector<ros2::OdometryNodeOutput>& outputs) {
    for (const ros2::OdometryNodeOutput& o : outputs) {
      odometry.write(io::encode_ros2(o.odometry));
      if (tf) tf->write(io::encode_ros2(o.transform));
    }
  };
  // Each source wakes the loop at once in turn; a source gone quiet is given up within the
  // loop's waits (source_timeout_s is checked at every pass).
  while (!g_stop) {
    for (const auto& bytes : wheels.take(kLoopWaitS / 2)) {
      if (settings.wheels_as_odometry) {
        if (auto m = decoded(rt, bytes, io::decode_ros2_odometry)) {
          publish(core.wheel_odometry(*m, steady_seconds(), rt.ros_time()));
        }
      } else if (auto m = decoded(rt, bytes, io::decode_ros2_joint_state)) {
        publish(core.joint_state(*m, steady_seconds(), rt.ros_time()));
      }
    }
    for (const auto& bytes : imu.take(kLoopWaitS / 2)) {
      if (auto m = decoded(rt, bytes, io::decode_ros2_imu)) {
        publish(core.imu(*m, steady_seconds(), rt.ros_time()));
      }
    }
    const double now_s = steady_seconds();
    publish(core.poll(now_s));
    rt.report(now_s);
    if (rt.diagnostics_due(now_s)) rt.publish_diagnostics(core.diagnostics(rt.undecodable()));
  }
  publish(core.poll(steady_seconds()));
  const pipeline::OdometryArrivals& aw = core.runner().arrivals(pipeline::OdometrySource::kWheels);
  const pipeline::OdometryArrivals& ai = core.runner().arrivals(pipeline::OdometrySource::kImu);
  std::fprintf(stderr,
               "dispel-ros2 odometry: %lld wheel and %lld IMU measurements in, %lld estimates "
               "published, %lld wheel and %lld IMU measurements late, %lld wheel messages without "
               "both wheels, %lld undecodable messages\n",
               static_cast<long long>(aw.count), static_cast<long long>(ai.count),
               static_cast<long long>(core.published()),
               static_cast<long long>(core.runner().late(pipeline::OdometrySource::kWheels)),
               static_cast<long long>(core.runner().late(pipeline::OdometrySource::kImu)),
               static_cast<long long>(core.malformed()), static_cast<long long>(rt.undecodable()));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || (args[0] != "filter" && args[0] != "odometry")) {
    return usage(args.empty() ? "no command" : "unknown command " + io::quote(args[0]));
  }
  const bool filter = args[0] == "filter";
  // Before DDS starts its threads: the filter's first scans do not wait for fresh memory.
  if (filter) pipeline::reserve_resident_heap(pipeline::kDefaultResidentHeapBytes);
  std::vector<std::string> params_files;
  std::vector<ros2::ParameterText> overrides;  // -p name:=value, after the files, as rcl.
  std::string node_name = filter ? "dispel_filter" : "dispel_odometry";
  for (std::size_t k = 1; k < args.size(); ++k) {
    const std::string& a = args[k];
    const bool has_value = k + 1 < args.size();
    if (a == "--ros-args" || a == "--") continue;
    if (a == "--params-file" && has_value) {
      params_files.push_back(args[++k]);
    } else if (a == "--node-name" && has_value) {
      node_name = args[++k];
    } else if (a == "-r" && has_value && args[k + 1].rfind("__node:=", 0) == 0) {
      node_name = args[++k].substr(8);
    } else if (a == "-r" && has_value && args[k + 1].rfind("__ns:=", 0) == 0) {
      const std::string ns = args[++k].substr(6);
      if (ns != "/") {
        return usage("namespace " + io::quote(ns) +
                     ": only / is supported (give the topics whole in the parameters)");
      }
    } else if (a == "-r" && has_value) {
      return usage("remapping " + io::quote(args[k + 1]) +
                   " is not supported: set the node's topic parameters (docs/ros2.md)");
    } else if (a == "-p" && has_value) {
      const std::string& assignment = args[++k];
      const std::size_t at = assignment.find(":=");
      const std::string name = assignment.substr(0, at);
      if (at == std::string::npos || name.empty() ||
          name.find_first_not_of(
              "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") !=
              std::string::npos) {
        return usage("-p " + io::quote(assignment) + " is not name:=value");
      }
      overrides.push_back(
          {"/**:\n  ros__parameters:\n    " + name + ": " + assignment.substr(at + 2) + "\n",
           "-p " + assignment});
    } else {
      return usage("unknown or incomplete argument " + io::quote(a));
    }
  }
  const bool valid_name =
      !node_name.empty() && !(node_name[0] >= '0' && node_name[0] <= '9') &&
      node_name.find_first_not_of(
          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") == std::string::npos;
  if (!valid_name) {
    return usage("the node name " + io::quote(node_name) +
                 " is not a ROS 2 node name (letters, digits and '_', not starting with a digit)");
  }
  try {
    std::vector<ros2::ParameterText> parameters;
    for (const std::string& path : params_files) {
      parameters.push_back({io::read_regular_file(path, "parameter file"), path});
    }
    parameters.insert(parameters.end(), overrides.begin(), overrides.end());
    if (filter) return run_filter(ros2::parse_filter_node_parameters(parameters, node_name));
    return run_odometry(ros2::parse_odometry_node_parameters(parameters, node_name));
  } catch (const io::InputError& e) {
    std::fprintf(stderr, "dispel-ros2: %s\n", io::one_line(e.what()).c_str());
    return 2;
  } catch (const std::invalid_argument& e) {  // A configuration the runners refuse.
    std::fprintf(stderr, "dispel-ros2: %s\n", io::one_line(e.what()).c_str());
    return 2;
  } catch (const ros2::DdsError& e) {
    std::fprintf(stderr, "dispel-ros2: %s\n", io::one_line(e.what()).c_str());
    return 3;
  } catch (const std::exception& e) {  // Out of memory, say: said, not an abort.
    std::fprintf(stderr, "dispel-ros2: %s\n", io::one_line(e.what()).c_str());
    return 3;
  }
}
