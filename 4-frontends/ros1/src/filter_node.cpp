// dispel_filter_node: the dynamic object filter between a LiDAR driver and SLAM.
// Subscribes `scan`; publishes `scan_filtered`, `scan_labels`, `~objects` and /diagnostics.
// Parameters: the node's own (below) and the filter's, under the names of config/default.yaml.
// The per-scan work is FilterNodeCore's (filter_node_core.hpp), shared with `dispel filter`'s
// runner; this file is the middleware around it.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/frame_tree.hpp"
#include "dispel/io/ros1_messages.hpp"
#include "dispel/pipeline/resident_heap.hpp"
#include "dispel/ros1/convert.hpp"
#include "dispel/ros1/filter_node_core.hpp"
#include "dispel/ros1/parameters.hpp"

namespace dispel::ros1 {
namespace {

struct FilterNodeSettings {
  std::string fixed_frame = "odom";     ///< The frame objects are tracked in.
  bool static_sensor = false;           ///< The sensor does not move: identity pose, no TF.
  double transform_timeout_s = 0.1;     ///< Longest wait for the sensor pose at a scan's stamp.
  bool drop_without_transform = false;  ///< Else published unfiltered.
  int queue_size = 10;
  bool publish_objects = true;
  double diagnostics_period_s = 1.0;
  pipeline::ScanFilterRunnerOptions runner;
};

FilterNodeSettings read_settings(const std::string& node_name) {
  XmlRpc::XmlRpcValue tree;
  ros::param::get(node_name, tree);
  NodeParameters p(tree, node_name + "/");
  FilterNodeSettings s;
  s.fixed_frame = io::FrameTree::normalise(p.text("fixed_frame", s.fixed_frame));
  if (s.fixed_frame.empty()) throw ParameterError(node_name + "/fixed_frame must not be empty");
  s.static_sensor = p.boolean("static_sensor", s.static_sensor);
  s.runner.static_sensor = s.static_sensor;
  s.transform_timeout_s = p.number("transform_timeout_s", s.transform_timeout_s);
  p.require(std::isfinite(s.transform_timeout_s) && s.transform_timeout_s >= 0.0,
            "transform_timeout_s", "a finite number >= 0", s.transform_timeout_s);
  s.drop_without_transform = p.choice("on_missing_transform", "publish_unfiltered",
                                      {"publish_unfiltered", "drop"}) == "drop";
  s.runner.scale_to_scanner = p.boolean("scale_to_scanner", false);
  s.runner.scan_period_s = p.number("scan_period_s", 0.0);
  p.require(std::isfinite(s.runner.scan_period_s) && s.runner.scan_period_s >= 0.0, "scan_period_s",
            "a finite number >= 0 (0: from the scans)", s.runner.scan_period_s);
  s.queue_size = p.integer("queue_size", s.queue_size);
  p.require(s.queue_size >= 1, "queue_size", "an integer >= 1", s.queue_size);
  s.publish_objects = p.boolean("publish_objects", s.publish_objects);
  s.diagnostics_period_s = p.number("diagnostics_period_s", s.diagnostics_period_s);
  p.require(std::isfinite(s.diagnostics_period_s) && s.diagnostics_period_s > 0.0,
            "diagnostics_period_s", "a finite number > 0", s.diagnostics_period_s);
  // Everything else is the filter's: the same parser, keys and messages as `dispel filter`.
  s.runner.config =
      io::parse_filter_config(to_yaml(p.tree(), p.keys()), "parameters of " + node_name);
  return s;
}

class FilterNode {
 public:
  FilterNode(ros::NodeHandle& nh, ros::NodeHandle& private_nh, FilterNodeSettings settings)
      : settings_(std::move(settings)), core_(settings_.runner) {
    if (!settings_.static_sensor) listener_.emplace(tf_buffer_);
    filtered_pub_ = nh.advertise<sensor_msgs::LaserScan>("scan_filtered", settings_.queue_size);
    labels_pub_ = nh.advertise<sensor_msgs::LaserScan>("scan_labels", settings_.queue_size);
    objects_pub_ = private_nh.advertise<visualization_msgs::MarkerArray>("objects", 2);
    diagnostics_pub_ = nh.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 2);
    scan_sub_ = nh.subscribe("scan", static_cast<std::uint32_t>(settings_.queue_size),
                             &FilterNode::on_scan, this, ros::TransportHints().tcpNoDelay());
    diagnostics_timer_ = nh.createSteadyTimer(ros::WallDuration(settings_.diagnostics_period_s),
                                              &FilterNode::publish_diagnostics, this);
    ROS_INFO("dispel filter: %s -> %s, %s; sensor pose %s%s", scan_sub_.getTopic().c_str(),
             filtered_pub_.getTopic().c_str(), labels_pub_.getTopic().c_str(),
             settings_.static_sensor ? "fixed (static_sensor)" : "in ",
             settings_.static_sensor ? "" : settings_.fixed_frame.c_str());
  }

 private:
  void on_scan(const sensor_msgs::LaserScan::ConstPtr& msg) {
    std::optional<Pose2> pose;
    if (settings_.static_sensor) {
      pose = Pose2{};
    } else {
      try {
        const geometry_msgs::TransformStamped t = tf_buffer_.lookupTransform(
            settings_.fixed_frame, io::FrameTree::normalise(msg->header.frame_id),
            msg->header.stamp, ros::Duration(settings_.transform_timeout_s));
        pose = io::from_ros(t.transform);
      } catch (const tf2::TransformException& e) {
        ++no_transform_;
        ++window_no_transform_;
        ROS_WARN_THROTTLE(
            5.0, "dispel filter: no pose of '%s' in '%s' at %.3f, scan %s: %s",
            msg->header.frame_id.c_str(), settings_.fixed_frame.c_str(), msg->header.stamp.toSec(),
            settings_.drop_without_transform ? "dropped" : "published unfiltered", e.what());
        if (settings_.drop_without_transform) {
          ++dropped_;
          return;
        }
      }
    }
    const FilterNodeCore::Output out = core_.process(*msg, ros::Time::now().toSec(), pose);
    filtered_pub_.publish(out.filtered);
    labels_pub_.publish(out.labels);
    if (settings_.publish_objects && objects_pub_.getNumSubscribers() > 0) {
      std_msgs::Header header = msg->header;
      // Tracks are in the fixed frame; for a static sensor that is the sensor's own.
      header.frame_id = settings_.static_sensor ? io::FrameTree::normalise(header.frame_id)
                                                : settings_.fixed_frame;
      objects_pub_.publish(object_markers(out.result->tracks, header));
    }
  }

  void publish_diagnostics(const ros::SteadyTimerEvent&) {
    diagnostic_msgs::DiagnosticArray array;
    array.header.stamp = ros::Time::now();
    array.status.push_back(
        to_ros(pipeline::filter_node_status(ros::this_node::getName(), core_.runner(),
                                            {no_transform_, window_no_transform_, dropped_})));
    window_no_transform_ = 0;
    diagnostics_pub_.publish(array);
  }

  FilterNodeSettings settings_;
  FilterNodeCore core_;
  tf2_ros::Buffer tf_buffer_;
  std::optional<tf2_ros::TransformListener> listener_;
  ros::Publisher filtered_pub_, labels_pub_, objects_pub_, diagnostics_pub_;
  ros::Subscriber scan_sub_;
  ros::SteadyTimer diagnostics_timer_;
  std::int64_t no_transform_ = 0;
  std::int64_t window_no_transform_ = 0;
  std::int64_t dropped_ = 0;
};

}  // namespace
}  // namespace dispel::ros1

int main(int argc, char** argv) {
  // Before ROS starts its threads: the filter's first scans do not wait for fresh memory.
  dispel::pipeline::reserve_resident_heap(dispel::pipeline::kDefaultResidentHeapBytes);
  ros::init(argc, argv, "dispel_filter");
  ros::NodeHandle nh;
  ros::NodeHandle private_nh("~");
  std::optional<dispel::ros1::FilterNode> node;
  try {
    node.emplace(nh, private_nh, dispel::ros1::read_settings(ros::this_node::getName()));
  } catch (const std::exception& e) {  // ParameterError, io::ConfigError, std::invalid_argument
    ROS_FATAL("dispel_filter_node: bad parameter: %s", e.what());
    return 1;
  }
  ros::spin();
  return 0;
}
