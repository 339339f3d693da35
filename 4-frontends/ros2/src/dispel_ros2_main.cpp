// dispel-ros2: dispel's nodes on ROS 2, as DDS participants that follow ROS 2's mapping onto DDS
// (Cyclone DDS; docs/ros2.md). No ROS 2 install is needed, on this machine or the robot's.
//
//   dispel-ros2 filter [--params-file FILE] [--node-name NAME]
//   dispel-ros2 filter --ros-args [--params-file FILE] [-r __node:=NAME]   (as ros2 launch runs it)
//
// filter: subscribes <scan_topic> (sensor_msgs/LaserScan, best effort: any driver's QoS), /tf
// and /tf_static; publishes <scan_topic>_filtered (removed beams NaN) and <scan_topic>_labels
// (intensities = beam labels), reliable. The per-scan work is FilterNodeCore's; this file is the
// middleware around it. Ctrl-C or SIGTERM stops it after the scan in hand; it then prints its
// counts. Exit status: 0, 2 for a bad command line or parameter file, 3 for a DDS failure.
#include <signal.h>

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
#include "dispel/ros2/dds.hpp"
#include "dispel/ros2/filter_node.hpp"
#include "dispel/ros2/graph.hpp"

namespace {

using namespace dispel;

std::atomic<bool> g_stop{false};

void on_signal(int) { g_stop = true; }

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

int usage(const std::string& problem) {
  std::fprintf(stderr,
               "dispel-ros2: %s\nusage: dispel-ros2 filter [--params-file FILE] [--node-name "
               "NAME]\n       dispel-ros2 filter --ros-args [--params-file FILE] [-r "
               "__node:=NAME]\n",
               problem.c_str());
  return 2;
}

int run_filter(const ros2::FilterNodeSettings& settings) {
  ros2::Participant participant(ros2::domain_from_environment());
  const std::string scan_type = "sensor_msgs/msg/LaserScan";
  const std::string tf_type = "tf2_msgs/msg/TFMessage";
  // A best-effort reader matches best-effort and reliable drivers alike.
  ros2::Reader scans(participant, settings.scan_topic, scan_type, ros2::Qos::sensor_data());
  ros2::Reader tf(participant, "/tf", tf_type,
                  {ros2::Qos::Reliability::kReliable, ros2::Qos::Durability::kVolatile, 100});
  ros2::Reader tf_static(participant, "/tf_static", tf_type, ros2::Qos::tf_static_subscriber());
  ros2::Writer filtered(participant, settings.scan_topic + "_filtered", scan_type,
                        ros2::Qos::defaults());
  ros2::Writer labels(participant, settings.scan_topic + "_labels", scan_type,
                      ros2::Qos::defaults());
  // use_sim_time: ROS time is /clock's (ROS 2's clock QoS: best effort, keep last 1).
  std::optional<ros2::Reader> clock;
  if (settings.use_sim_time) {
    clock.emplace(
        participant, "/clock", "rosgraph_msgs/msg/Clock",
        ros2::Qos{ros2::Qos::Reliability::kBestEffort, ros2::Qos::Durability::kVolatile, 1});
  }
  double sim_time_s = 0.0;
  const auto ros_time_s = [&] {
    if (clock) {
      for (const auto& bytes : clock->take(0.0)) {
        try {
          sim_time_s = ros2::decode_clock(bytes);
        } catch (const io::CdrError&) {
        }
      }
      return sim_time_s;
    }
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
        .count();
  };
  ros2::FilterNodeCore core(settings);

  // The node in ROS 2's graph (ros2 node list), in the layout of the robot's distribution.
  std::string distro = settings.ros_distro;  // Checked when the parameters were read.
  if (distro.empty()) {
    const char* env = std::getenv("ROS_DISTRO");
    distro = env != nullptr && *env != '\0' ? env : "humble";
    try {
      ros2::gid_layout_named(distro);
    } catch (const ros2::DdsError&) {  // A ROS 1 shell's "noetic", say.
      std::fprintf(stderr,
                   "dispel-ros2 filter: warning: ROS_DISTRO=%s is not a ROS 2 distribution this "
                   "node knows; its graph uses humble's layout (set ros_distro to choose)\n",
                   io::one_line(distro, 40).c_str());
      distro = "humble";
    }
  }
  const ros2::GidLayout layout = ros2::gid_layout_named(distro);
  ros2::Writer graph(participant, ros2::discovery_topic(), ros2::discovery_qos());
  ros2::NodeEntities node{"/", settings.node_name, {}, {}};
  node.readers = {scans.guid(), tf.guid(), tf_static.guid()};
  node.writers = {filtered.guid(), labels.guid()};
  graph.write(ros2::encode_participant_entities(participant.guid(), {node}, layout));

  struct sigaction action {};
  action.sa_handler = on_signal;
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
  std::fprintf(stderr,
               "dispel-ros2 filter: node /%s on domain %d (graph in %s's layout): %s -> "
               "%s_filtered, %s_labels\n",
               settings.node_name.c_str(), participant.domain_id(), distro.c_str(),
               settings.scan_topic.c_str(), settings.scan_topic.c_str(),
               settings.scan_topic.c_str());

  const auto take_transforms = [&](ros2::Reader& reader, bool is_static) {
    for (const auto& bytes : reader.take(0.0)) {
      try {
        core.transforms(io::decode_ros2_transforms(bytes.data(), bytes.size()), is_static);
      } catch (const io::CdrError&) {
        core.count_undecodable();
      }
    }
  };
  const auto publish = [&](const std::vector<ros2::FilterNodeOutput>& outputs) {
    for (const ros2::FilterNodeOutput& o : outputs) {
      filtered.write(io::encode_ros2(o.filtered));
      labels.write(io::encode_ros2(o.labels));
    }
  };
  // Connections are said as they change (a driver found, SLAM subscribed), and a QoS that keeps
  // an endpoint of another node from matching is said once per endpoint (DDS counts them), not
  // left silent.
  struct Watched {
    const char* what;
    const char* topic;
    int reported = 0;
    int connected = 0;
  };
  const std::string filtered_topic = settings.scan_topic + "_filtered";
  const std::string labels_topic = settings.scan_topic + "_labels";
  Watched watched[] = {{"a publisher of", settings.scan_topic.c_str()},
                       {"a publisher of", "/tf"},
                       {"a publisher of", "/tf_static"},
                       {"a subscriber of", filtered_topic.c_str()},
                       {"a subscriber of", labels_topic.c_str()}};
  const auto report_connections = [&] {
    const ros2::Matches now[] = {scans.matches(), tf.matches(), tf_static.matches(),
                                 filtered.matches(), labels.matches()};
    for (std::size_t k = 0; k < 5; ++k) {
      if (now[k].current != watched[k].connected) {
        watched[k].connected = now[k].current;
        std::fprintf(stderr, "dispel-ros2 filter: %s: %d %s matched\n", watched[k].topic,
                     now[k].current, k < 3 ? "publishers" : "subscribers");
      }
      if (now[k].incompatible <= watched[k].reported) continue;
      watched[k].reported = now[k].incompatible;
      std::fprintf(stderr,
                   "dispel-ros2 filter: warning: %s %s has a QoS this node cannot match (%s); it "
                   "is not connected\n",
                   watched[k].what, watched[k].topic, now[k].last_incompatible_policy.c_str());
    }
  };
  double next_check_s = 0.0;
  // A scan wakes the loop at once; transforms are taken before each scan, and a scan waiting for
  // its pose is looked at again within the wait (20 ms).
  constexpr double kWaitS = 0.02;
  while (!g_stop) {
    take_transforms(tf_static, true);
    take_transforms(tf, false);
    for (const auto& bytes : scans.take(kWaitS)) {
      take_transforms(tf_static, true);
      take_transforms(tf, false);
      io::ScanMessage message;
      try {
        message = io::decode_ros2_scan(bytes.data(), bytes.size());
      } catch (const io::CdrError&) {
        core.count_undecodable();
        continue;
      }
      publish(core.scan(std::move(message), steady_seconds(), ros_time_s()));
    }
    const double now_s = steady_seconds();
    publish(core.poll(now_s));
    if (now_s >= next_check_s) {
      report_connections();
      next_check_s = now_s + 0.5;
    }
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
               static_cast<long long>(c.dropped_queue_full), static_cast<long long>(c.undecodable),
               static_cast<long long>(c.transforms_refused), static_cast<long long>(c.time_resets),
               static_cast<long long>(c.zero_stamps));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] != "filter") {
    return usage(args.empty() ? "no command" : "unknown command " + io::quote(args[0]));
  }
  std::string params_file;
  std::string node_name = "dispel_filter";
  for (std::size_t k = 1; k < args.size(); ++k) {
    const std::string& a = args[k];
    const bool has_value = k + 1 < args.size();
    if (a == "--ros-args" || a == "--") continue;
    if (a == "--params-file" && has_value) {
      params_file = args[++k];
    } else if (a == "--node-name" && has_value) {
      node_name = args[++k];
    } else if (a == "-r" && has_value && args[k + 1].rfind("__node:=", 0) == 0) {
      node_name = args[++k].substr(8);
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
    const std::string text =
        params_file.empty() ? std::string() : io::read_regular_file(params_file, "parameter file");
    const ros2::FilterNodeSettings settings = ros2::parse_filter_node_parameters(
        text, params_file.empty() ? "parameters" : params_file, node_name);
    return run_filter(settings);
  } catch (const io::InputError& e) {
    std::fprintf(stderr, "dispel-ros2: %s\n", io::one_line(e.what()).c_str());
    return 2;
  } catch (const ros2::DdsError& e) {
    std::fprintf(stderr, "dispel-ros2: %s\n", io::one_line(e.what()).c_str());
    return 3;
  }
}
