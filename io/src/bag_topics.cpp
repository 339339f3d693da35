#include "dispel/io/bag_topics.hpp"

#include <rosbag/view.h>

#include "dispel/io/filter_job.hpp"

namespace dispel::io {

void open_bag_for_reading(rosbag::Bag& bag, const std::string& path) {
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw JobError(path + ": not a readable ROS 1 bag (" + e.what() + ")");
  }
}

BagTopics::BagTopics(const rosbag::Bag& bag) {
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* c : all.getConnections()) {
    type_of_topic_[c->topic] = c->datatype;
  }
}

bool BagTopics::has(const std::string& topic, const std::string& type) const {
  const auto it = type_of_topic_.find(topic);
  return it != type_of_topic_.end() && it->second == type;
}

std::vector<std::string> BagTopics::of_type(const std::string& type) const {
  std::vector<std::string> topics;
  for (const auto& [topic, t] : type_of_topic_) {
    if (t == type) topics.push_back(topic);
  }
  return topics;
}

std::string BagTopics::list(const std::string& type) const { return join_topics(of_type(type)); }

void rethrow_as_recording_error(const std::string& path) {
  try {
    throw;
  } catch (const JobError&) {
    throw;
  } catch (const JobCancelled&) {
    throw;
  } catch (const std::exception& e) {
    throw JobError(path + ": cannot read the recording (" + e.what() +
                   "); it may be truncated or corrupt");
  }
}

std::string join_topics(const std::vector<std::string>& topics) {
  std::string s;
  for (const auto& t : topics) s += (s.empty() ? "" : ", ") + t;
  return s.empty() ? std::string("none") : s;
}

}  // namespace dispel::io
