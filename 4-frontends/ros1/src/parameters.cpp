#include "dispel/ros1/parameters.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace dispel::ros1 {
namespace {

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", static_cast<unsigned char>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string yaml_number(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// XmlRpcValue's accessors are not const; the values are copied, which is cheap for parameters.
void write(std::ostream& out, XmlRpc::XmlRpcValue v, const std::set<std::string>& skip,
           const std::string& path) {
  using V = XmlRpc::XmlRpcValue;
  switch (v.getType()) {
    case V::TypeBoolean:
      out << (static_cast<bool>(v) ? "true" : "false");
      return;
    case V::TypeInt:
      out << static_cast<int>(v);
      return;
    case V::TypeDouble:
      out << yaml_number(static_cast<double>(v));
      return;
    case V::TypeString:
      out << quoted(static_cast<std::string>(v));
      return;
    case V::TypeArray: {
      out << '[';
      for (int i = 0; i < v.size(); ++i) {
        if (i > 0) out << ", ";
        write(out, v[i], {}, path + "[" + std::to_string(i) + "]");
      }
      out << ']';
      return;
    }
    case V::TypeStruct: {
      out << '{';
      bool first = true;
      for (auto it = v.begin(); it != v.end(); ++it) {
        if (skip.count(it->first) != 0) continue;
        out << (first ? "" : ", ") << quoted(it->first) << ": ";
        write(out, it->second, {}, path.empty() ? it->first : path + "/" + it->first);
        first = false;
      }
      out << '}';
      return;
    }
    case V::TypeInvalid:
      out << "null";
      return;
    default:
      throw ParameterError("~" + path + ": a parameter of this type (base64, date) is not used");
  }
}

std::string shown(XmlRpc::XmlRpcValue v) {
  std::ostringstream out;
  try {
    write(out, std::move(v), {}, "");
  } catch (const ParameterError&) {
    return "?";
  }
  return out.str();
}

}  // namespace

std::string to_yaml(const XmlRpc::XmlRpcValue& tree, const std::set<std::string>& skip) {
  if (tree.getType() == XmlRpc::XmlRpcValue::TypeInvalid) return "{}";
  std::ostringstream out;
  write(out, tree, skip, "");
  return out.str() + "\n";
}

NodeParameters::NodeParameters(const XmlRpc::XmlRpcValue& tree, std::string prefix)
    : tree_(tree), prefix_(std::move(prefix)) {
  if (tree_.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    tree_ = XmlRpc::XmlRpcValue();
    tree_.begin();  // Makes it an empty struct.
  }
}

std::set<std::string> NodeParameters::members() const {
  std::set<std::string> names;
  for (auto it = tree_.begin(); it != tree_.end(); ++it) names.insert(it->first);
  return names;
}

XmlRpc::XmlRpcValue* NodeParameters::find(const std::string& key) {
  keys_.insert(key);
  return tree_.hasMember(key) ? &tree_[key] : nullptr;
}

void NodeParameters::wrong(const std::string& key, const char* what,
                           const XmlRpc::XmlRpcValue& value) const {
  throw ParameterError(prefix_ + key + " must be " + what + ", got " + shown(value));
}

void NodeParameters::require(bool ok, const std::string& key, const std::string& what,
                             double value) const {
  if (!ok) throw ParameterError(prefix_ + key + " must be " + what + ", got " + yaml_number(value));
}

std::string NodeParameters::text(const std::string& key, const std::string& fallback) {
  XmlRpc::XmlRpcValue* v = find(key);
  if (v == nullptr) return fallback;
  if (v->getType() != XmlRpc::XmlRpcValue::TypeString) wrong(key, "a string", *v);
  return static_cast<std::string>(*v);
}

std::string NodeParameters::choice(const std::string& key, const std::string& fallback,
                                   const std::set<std::string>& choices) {
  const std::string value = text(key, fallback);
  if (choices.count(value) == 0) {
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
    throw ParameterError(prefix_ + key + " must be one of " + list + ", got '" + value + "'");
  }
  return value;
}

double NodeParameters::number(const std::string& key, double fallback) {
  XmlRpc::XmlRpcValue* v = find(key);
  if (v == nullptr) return fallback;
  if (v->getType() == XmlRpc::XmlRpcValue::TypeDouble) return static_cast<double>(*v);
  if (v->getType() == XmlRpc::XmlRpcValue::TypeInt) return static_cast<int>(*v);
  wrong(key, "a number", *v);
}

int NodeParameters::integer(const std::string& key, int fallback) {
  XmlRpc::XmlRpcValue* v = find(key);
  if (v == nullptr) return fallback;
  if (v->getType() != XmlRpc::XmlRpcValue::TypeInt) wrong(key, "an integer", *v);
  return static_cast<int>(*v);
}

bool NodeParameters::boolean(const std::string& key, bool fallback) {
  XmlRpc::XmlRpcValue* v = find(key);
  if (v == nullptr) return fallback;
  if (v->getType() != XmlRpc::XmlRpcValue::TypeBoolean) wrong(key, "true or false", *v);
  return static_cast<bool>(*v);
}

}  // namespace dispel::ros1
