#pragma once
/// @file
/// Opening a ROS 1 bag for reading and asking which topics it holds, with the one-line errors
/// every dispel command gives.

#include <rosbag/bag.h>

#include <map>
#include <string>
#include <vector>

namespace dispel::io {

/// Opens @p path for reading. @throws JobError "<path>: not a readable ROS 1 bag (...)"
void open_bag_for_reading(rosbag::Bag& bag, const std::string& path);

/// The topics of an open bag and their message types.
class BagTopics {
 public:
  explicit BagTopics(const rosbag::Bag& bag);

  /// Whether @p topic is in the bag with messages of @p type ("sensor_msgs/LaserScan").
  bool has(const std::string& topic, const std::string& type) const;
  /// Whether @p topic is in the bag at all.
  bool has(const std::string& topic) const { return type_of_topic_.count(topic) != 0; }
  /// The topics with messages of @p type, in name order.
  std::vector<std::string> of_type(const std::string& type) const;
  /// The same as "a, b, c", or "none": for error messages.
  std::string list(const std::string& type) const;

 private:
  std::map<std::string, std::string> type_of_topic_;
};

/// For `catch (...)` around reading a recording: rethrows a JobError or JobCancelled as it is,
/// and any other std::exception (the bag library's, on a truncated or corrupt file) as
/// JobError "<path>: cannot read the recording (...); it may be truncated or corrupt".
[[noreturn]] void rethrow_as_recording_error(const std::string& path);

/// "a, b, c" of @p topics, or "none".
std::string join_topics(const std::vector<std::string>& topics);

}  // namespace dispel::io
