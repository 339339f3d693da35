#include "dispel/ros2/dds.hpp"

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>
#include <dds/ddsi/q_radmin.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>

namespace dispel::ros2 {
namespace {

// Raw CDR as a Cyclone type: a sample is a std::vector<std::uint8_t> holding a message's CDR
// with its encapsulation header, and Cyclone carries those bytes as they are. This is how ROS 2's
// own Cyclone RMW carries its messages (its sertype of serialised messages): keyless, XCDR1, no
// XTypes type information, so endpoints match on topic and type name as they do with it.
using Sample = std::vector<std::uint8_t>;

struct RawType : ddsi_sertype {};

struct RawData : ddsi_serdata {
  std::vector<std::uint8_t> bytes;  // Padded with zeros to a multiple of 4, as DDS sends them.
  std::uint32_t size = 0;           // Without the padding.
};

// Cyclone calls the operations below from its own C threads: none may throw. Out of memory,
// they return null (or false), as Cyclone's own do.
RawData* make_data(const ddsi_sertype* type, ddsi_serdata_kind kind, std::size_t size) noexcept {
  if (size > std::numeric_limits<std::uint32_t>::max()) return nullptr;
  auto* d = new (std::nothrow) RawData();
  if (d == nullptr) return nullptr;
  try {
    d->bytes.assign((size + 3) / 4 * 4, 0);
  } catch (...) {
    delete d;
    return nullptr;
  }
  ddsi_serdata_init(d, type, kind);
  d->hash = type->serdata_basehash;  // Keyless: one instance.
  d->size = static_cast<std::uint32_t>(size);
  return d;
}

const RawData* raw(const ddsi_serdata* d) { return static_cast<const RawData*>(d); }

// --- The serialised data's operations.
bool data_eqkey(const ddsi_serdata*, const ddsi_serdata*) { return true; }  // Keyless.
std::uint32_t data_size(const ddsi_serdata* d) { return raw(d)->size; }

ddsi_serdata* data_from_ser(const ddsi_sertype* type, ddsi_serdata_kind kind,
                            const nn_rdata* fragchain, std::size_t size) {
  RawData* d = make_data(type, kind, size);
  if (d == nullptr) return nullptr;
  // The fragments cover [0, size) in order, possibly overlapping: each adds what lies past the
  // previous one's end.
  std::size_t off = 0;
  for (const nn_rdata* f = fragchain; f != nullptr; f = f->nextfrag) {
    if (f->maxp1 > off && f->min <= off) {
      const auto* payload = reinterpret_cast<const std::uint8_t*>(
          NN_RMSG_PAYLOADOFF(f->rmsg, NN_RDATA_PAYLOAD_OFF(f)));
      const std::size_t end = std::min<std::size_t>(f->maxp1, size);
      std::memcpy(d->bytes.data() + off, payload + (off - f->min), end - off);
      off = end;
    }
  }
  return d;
}

ddsi_serdata* data_from_ser_iov(const ddsi_sertype* type, ddsi_serdata_kind kind,
                                ddsrt_msg_iovlen_t niov, const ddsrt_iovec_t* iov,
                                std::size_t size) {
  RawData* d = make_data(type, kind, size);
  if (d == nullptr) return nullptr;
  std::size_t off = 0;
  for (ddsrt_msg_iovlen_t k = 0; k < niov && off < size; ++k) {
    const std::size_t n = std::min<std::size_t>(iov[k].iov_len, size - off);
    std::memcpy(d->bytes.data() + off, iov[k].iov_base, n);
    off += n;
  }
  return d;
}

ddsi_serdata* data_from_keyhash(const ddsi_sertype* type, const ddsi_keyhash*) {
  return make_data(type, SDK_KEY, 0);
}

ddsi_serdata* data_from_sample(const ddsi_sertype* type, ddsi_serdata_kind kind,
                               const void* sample) {
  const auto& bytes = *static_cast<const Sample*>(sample);
  if (kind != SDK_DATA) return make_data(type, kind, 0);
  RawData* d = make_data(type, kind, bytes.size());
  if (d == nullptr) return nullptr;
  std::copy(bytes.begin(), bytes.end(), d->bytes.begin());
  return d;
}

void data_to_ser(const ddsi_serdata* d, std::size_t off, std::size_t sz, void* buf) {
  const auto& bytes = raw(d)->bytes;
  const std::size_t have = off < bytes.size() ? std::min(sz, bytes.size() - off) : 0;
  if (have > 0) std::memcpy(buf, bytes.data() + off, have);
  if (have < sz) std::memset(static_cast<char*>(buf) + have, 0, sz - have);
}

ddsi_serdata* data_to_ser_ref(const ddsi_serdata* d, std::size_t off, std::size_t sz,
                              ddsrt_iovec_t* ref) {
  auto* data = const_cast<RawData*>(raw(d));
  ref->iov_base = data->bytes.data() + std::min(off, data->bytes.size());
  ref->iov_len = static_cast<ddsrt_iov_len_t>(sz);
  return ddsi_serdata_ref(data);
}

void data_to_ser_unref(ddsi_serdata* d, const ddsrt_iovec_t*) { ddsi_serdata_unref(d); }

bool data_to_sample(const ddsi_serdata* d, void* sample, void**, void*) {
  const RawData* data = raw(d);
  auto& bytes = *static_cast<Sample*>(sample);
  try {
    bytes.assign(data->bytes.begin(), data->bytes.begin() + data->size);
  } catch (...) {
    return false;
  }
  return true;
}

ddsi_serdata* data_to_untyped(const ddsi_serdata* d) {
  RawData* key = make_data(d->type, SDK_KEY, 0);
  if (key == nullptr) return nullptr;
  key->type = nullptr;  // Untyped: the key alone, which a keyless type does not have.
  return key;
}

bool data_untyped_to_sample(const ddsi_sertype*, const ddsi_serdata*, void*, void**, void*) {
  return true;
}

void data_free(ddsi_serdata* d) { delete static_cast<RawData*>(d); }

std::size_t data_print(const ddsi_sertype*, const ddsi_serdata* d, char* buf, std::size_t size) {
  const std::string text = "(" + std::to_string(raw(d)->size) + " bytes of CDR)";
  const std::size_t n = std::min(text.size(), size - 1);
  std::memcpy(buf, text.data(), n);
  buf[n] = '\0';
  return text.size();
}

void data_get_keyhash(const ddsi_serdata*, ddsi_keyhash* buf, bool) {
  std::memset(buf->value, 0, sizeof buf->value);
}

const ddsi_serdata_ops kDataOps = [] {
  ddsi_serdata_ops ops{};
  ops.eqkey = data_eqkey;
  ops.get_size = data_size;
  ops.from_ser = data_from_ser;
  ops.from_ser_iov = data_from_ser_iov;
  ops.from_keyhash = data_from_keyhash;
  ops.from_sample = data_from_sample;
  ops.to_ser = data_to_ser;
  ops.to_ser_ref = data_to_ser_ref;
  ops.to_ser_unref = data_to_ser_unref;
  ops.to_sample = data_to_sample;
  ops.to_untyped = data_to_untyped;
  ops.untyped_to_sample = data_untyped_to_sample;
  ops.free = data_free;
  ops.print = data_print;
  ops.get_keyhash = data_get_keyhash;
  return ops;
}();

// --- The type's operations. Samples are Sample objects; dispel takes serialised data
// (dds_takecdr), so Cyclone makes or frees samples only for an application that asks it to.
void type_free(ddsi_sertype* t) {
  ddsi_sertype_fini(t);
  delete static_cast<RawType*>(t);
}

void type_zero_samples(const ddsi_sertype*, void* samples, std::size_t count) {
  auto* s = static_cast<Sample*>(samples);
  for (std::size_t k = 0; k < count; ++k) s[k].clear();
}

void type_realloc_samples(void** ptrs, const ddsi_sertype*, void* old, std::size_t oldcount,
                          std::size_t count) {
  auto* fresh = new Sample[count];
  auto* previous = static_cast<Sample*>(old);
  for (std::size_t k = 0; k < std::min(oldcount, count); ++k) fresh[k] = std::move(previous[k]);
  delete[] previous;
  for (std::size_t k = 0; k < count; ++k) ptrs[k] = &fresh[k];
}

void type_free_samples(const ddsi_sertype*, void** ptrs, std::size_t count, dds_free_op_t op) {
  if (count == 0) return;
  auto* samples = static_cast<Sample*>(ptrs[0]);
  if (op & DDS_FREE_ALL_BIT) {
    delete[] samples;
  } else {
    for (std::size_t k = 0; k < count; ++k) samples[k].clear();
  }
}

bool type_equal(const ddsi_sertype*, const ddsi_sertype*) { return true; }  // Names compared.
std::uint32_t type_hash(const ddsi_sertype*) { return 0; }

const ddsi_sertype_ops kTypeOps = [] {
  ddsi_sertype_ops ops{};
  ops.version = ddsi_sertype_v0;
  ops.free = type_free;
  ops.zero_samples = type_zero_samples;
  ops.realloc_samples = type_realloc_samples;
  ops.free_samples = type_free_samples;
  ops.equal = type_equal;
  ops.hash = type_hash;
  // get_serialized_size and serialize_into stay null: Cyclone 0.10 uses them only for shared
  // memory (iceoryx), whose receiving side this type does not implement; with them null it never
  // offers it.
  return ops;
}();

std::string dds_message(const std::string& what, dds_return_t rc) {
  return what + " (" + dds_strretcode(rc) + ")";
}

// A topic of @p type on the participant, its sertype (Cyclone's, which may be one it knew).
dds_entity_t make_topic(const Participant& participant, const DdsTopic& dds,
                        ddsi_sertype** actual) {
  const std::string& topic = dds.name;
  const std::string& type = dds.type;
  auto* t = new RawType();
  ddsi_sertype_init_flags(t, type.c_str(), &kTypeOps, &kDataOps,
                          DDSI_SERTYPE_FLAG_TOPICKIND_NO_KEY);
  t->allowed_data_representation = DDS_DATA_REPRESENTATION_FLAG_XCDR1;
  ddsi_sertype* st = t;
  const dds_entity_t handle =
      dds_create_topic_sertype(participant.handle(), topic.c_str(), &st, nullptr, nullptr, nullptr);
  if (handle < 0) {
    ddsi_sertype_unref(t);  // Still referenced once: unref frees it (type_free).
    throw DdsError(dds_message("cannot make the DDS topic " + topic + " of type " + type, handle));
  }
  *actual = st;
  return handle;
}

// The DDS QoS of a ROS 2 profile.
struct QosHandle {
  dds_qos_t* q;
  explicit QosHandle(const Qos& qos) : q(checked(qos)) {
    dds_qset_reliability(q,
                         qos.reliability == Qos::Reliability::kReliable
                             ? DDS_RELIABILITY_RELIABLE
                             : DDS_RELIABILITY_BEST_EFFORT,
                         DDS_SECS(1));
    dds_qset_durability(q, qos.durability == Qos::Durability::kTransientLocal
                               ? DDS_DURABILITY_TRANSIENT_LOCAL
                               : DDS_DURABILITY_VOLATILE);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, qos.depth);
    // As ROS 2's RMW sets them: a late joiner of a transient-local writer gets its whole history
    // (Cyclone takes it from the durability service's), and a writer that goes away leaves its
    // readers "no writers", not "disposed".
    if (qos.durability == Qos::Durability::kTransientLocal) {
      dds_qset_durability_service(q, 0, DDS_HISTORY_KEEP_LAST, qos.depth, DDS_LENGTH_UNLIMITED,
                                  DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
    }
    dds_qset_writer_data_lifecycle(q, false);
    const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
    dds_qset_data_representation(q, 1, &xcdr1);
  }
  static dds_qos_t* checked(const Qos& qos) {
    if (qos.depth < 1) throw DdsError("a QoS history depth must be at least 1");
    return dds_create_qos();
  }
  ~QosHandle() { dds_delete_qos(q); }
  QosHandle(const QosHandle&) = delete;
  QosHandle& operator=(const QosHandle&) = delete;
};

std::array<std::uint8_t, 16> guid_of(dds_entity_t entity) {
  dds_guid_t g;
  const dds_return_t rc = dds_get_guid(entity, &g);
  if (rc != DDS_RETCODE_OK) throw DdsError(dds_message("cannot get a DDS GUID", rc));
  std::array<std::uint8_t, 16> out{};
  std::memcpy(out.data(), g.v, out.size());
  return out;
}

std::string policy_name(dds_qos_policy_id_t id) {
  switch (id) {
    case DDS_RELIABILITY_QOS_POLICY_ID:
      return "reliability";
    case DDS_DURABILITY_QOS_POLICY_ID:
      return "durability";
    case DDS_HISTORY_QOS_POLICY_ID:
      return "history";
    case DDS_DEADLINE_QOS_POLICY_ID:
      return "deadline";
    case DDS_LIVELINESS_QOS_POLICY_ID:
      return "liveliness";
    case DDS_DATA_REPRESENTATION_QOS_POLICY_ID:
      return "data representation";
    case DDS_INVALID_QOS_POLICY_ID:
      return "";
    default:
      return "policy " + std::to_string(static_cast<int>(id));
  }
}

bool valid_name_character(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

}  // namespace

std::string dds_topic_name(const std::string& ros_topic) {
  // ROS 2's rules (design article "Topic and Service name mapping to DDS"): absolute, tokens of
  // letters, digits and '_' separated by single '/', none starting with a digit, no trailing '/'.
  bool valid = ros_topic.size() > 1 && ros_topic[0] == '/' && ros_topic.back() != '/';
  for (std::size_t k = 1; valid && k < ros_topic.size(); ++k) {
    const char c = ros_topic[k];
    if (c == '/') {
      valid = ros_topic[k - 1] != '/';
    } else {
      valid = valid_name_character(c) && !(ros_topic[k - 1] == '/' && c >= '0' && c <= '9');
    }
  }
  if (!valid) {
    throw DdsError("'" + ros_topic.substr(0, 200) +
                   "' is not an absolute ROS 2 topic name (/ then letters, digits, '_' and single "
                   "'/'; no token starting with a digit)");
  }
  return "rt" + ros_topic;
}

std::string dds_type_name(const std::string& ros_type) {
  std::vector<std::string> parts(1);
  for (const char c : ros_type) {
    if (c == '/') {
      parts.emplace_back();
    } else {
      parts.back() += c;
    }
  }
  if (parts.size() == 2) parts.insert(parts.begin() + 1, "msg");
  const bool valid = parts.size() == 3 && parts[1] == "msg" &&
                     std::all_of(parts.begin(), parts.end(), [](const std::string& p) {
                       return !p.empty() && std::all_of(p.begin(), p.end(), valid_name_character);
                     });
  if (!valid) {
    throw DdsError("'" + ros_type.substr(0, 200) +
                   "' is not a ROS 2 message type (package/msg/Name or package/Name)");
  }
  return parts[0] + "::msg::dds_::" + parts[2] + "_";
}

int domain_from_environment() {
  const char* value = std::getenv("ROS_DOMAIN_ID");
  if (value == nullptr || *value == '\0') return 0;
  const std::string text = value;
  const bool digits = text.size() <= 3 && std::all_of(text.begin(), text.end(),
                                                      [](char c) { return c >= '0' && c <= '9'; });
  const int id = digits ? std::stoi(text) : -1;
  if (id < 0 || id > 232) {
    throw DdsError("ROS_DOMAIN_ID='" + text.substr(0, 40) + "' is not an integer from 0 to 232");
  }
  return id;
}

Participant::Participant(int domain_id) : domain_id_(domain_id) {
  if (domain_id < 0 || domain_id > 232) {
    throw DdsError("the DDS domain " + std::to_string(domain_id) + " is not from 0 to 232");
  }
  dds_qos_t* qos = dds_create_qos();
  const std::string enclave = "enclave=/;";  // ROS 2's participant USER_DATA, no NUL.
  dds_qset_userdata(qos, enclave.data(), enclave.size());
  handle_ = dds_create_participant(static_cast<dds_domainid_t>(domain_id), qos, nullptr);
  dds_delete_qos(qos);
  if (handle_ < 0) {
    throw DdsError(dds_message(
        "cannot make a DDS participant in domain " + std::to_string(domain_id), handle_));
  }
}

Participant::~Participant() { dds_delete(handle_); }

std::array<std::uint8_t, 16> Participant::guid() const { return guid_of(handle_); }

Writer::Writer(Participant& participant, const DdsTopic& topic, const Qos& qos) {
  const QosHandle q(qos);
  const std::string& ros_topic = topic.name;
  topic_ = make_topic(participant, topic, &type_);
  writer_ = dds_create_writer(participant.handle(), topic_, q.q, nullptr);
  if (writer_ < 0) {
    dds_delete(topic_);
    throw DdsError(dds_message("cannot make a DDS writer of " + ros_topic, writer_));
  }
  // The statuses read by matches(), kept (not reset by a listener).
  dds_set_status_mask(writer_,
                      DDS_PUBLICATION_MATCHED_STATUS | DDS_OFFERED_INCOMPATIBLE_QOS_STATUS);
}

Writer::~Writer() {
  dds_delete(writer_);
  dds_delete(topic_);
}

void Writer::write(const std::vector<std::uint8_t>& cdr) {
  // The encapsulation header: XCDR1 (CDR_BE 0x0000 or CDR_LE 0x0001), as ROS 2 sends.
  if (cdr.size() < 4 || cdr[0] != 0 || cdr[1] > 1) {
    throw DdsError("a message to write is not CDR with its encapsulation header (" +
                   std::to_string(cdr.size()) + " bytes)");
  }
  ddsi_serdata* d = data_from_sample(type_, SDK_DATA, &cdr);
  if (d == nullptr) throw DdsError("a message is too large for DDS");
  // dds_writecdr takes the serdata's reference on every path a live writer can take.
  const dds_return_t rc = dds_writecdr(writer_, d);
  if (rc != DDS_RETCODE_OK) throw DdsError(dds_message("cannot write a DDS sample", rc));
}

Matches Writer::matches() const {
  Matches m;
  dds_publication_matched_status_t matched{};
  dds_get_publication_matched_status(writer_, &matched);
  m.current = static_cast<int>(matched.current_count);
  dds_offered_incompatible_qos_status_t incompatible{};
  dds_get_offered_incompatible_qos_status(writer_, &incompatible);
  m.incompatible = static_cast<int>(incompatible.total_count);
  m.last_incompatible_policy =
      policy_name(static_cast<dds_qos_policy_id_t>(incompatible.last_policy_id));
  return m;
}

std::array<std::uint8_t, 16> Writer::guid() const { return guid_of(writer_); }

Reader::Reader(Participant& participant, const DdsTopic& topic, const Qos& qos) {
  const QosHandle q(qos);
  const std::string& ros_topic = topic.name;
  ddsi_sertype* type = nullptr;
  topic_ = make_topic(participant, topic, &type);
  reader_ = dds_create_reader(participant.handle(), topic_, q.q, nullptr);
  if (reader_ < 0) {
    dds_delete(topic_);
    throw DdsError(dds_message("cannot make a DDS reader of " + ros_topic, reader_));
  }
  dds_set_status_mask(reader_, DDS_SUBSCRIPTION_MATCHED_STATUS |
                                   DDS_REQUESTED_INCOMPATIBLE_QOS_STATUS |
                                   DDS_DATA_AVAILABLE_STATUS);
  waitset_ = dds_create_waitset(participant.handle());
  condition_ = dds_create_readcondition(reader_, DDS_ANY_STATE);
  if (waitset_ < 0 || condition_ < 0 || dds_waitset_attach(waitset_, condition_, 0) < 0) {
    if (waitset_ >= 0) dds_delete(waitset_);
    dds_delete(reader_);
    dds_delete(topic_);
    throw DdsError("cannot make a DDS wait set for " + ros_topic);
  }
}

Reader::~Reader() {
  dds_delete(waitset_);
  dds_delete(reader_);  // Its read condition with it.
  dds_delete(topic_);
}

std::vector<std::vector<std::uint8_t>> Reader::take(double timeout_s) {
  std::vector<std::vector<std::uint8_t>> out;
  if (!(timeout_s >= 0.0)) timeout_s = 0.0;  // NaN too.
  const dds_duration_t timeout =
      timeout_s >= 1e9 ? DDS_INFINITY : static_cast<dds_duration_t>(std::llround(timeout_s * 1e9));
  if (dds_waitset_wait(waitset_, nullptr, 0, timeout) < 0) return out;
  constexpr std::uint32_t kBatch = 64;
  ddsi_serdata* samples[kBatch];
  dds_sample_info_t infos[kBatch];
  for (;;) {
    const dds_return_t n = dds_takecdr(reader_, samples, kBatch, infos, DDS_ANY_STATE);
    if (n <= 0) break;
    dds_return_t k = 0;
    try {
      for (; k < n; ++k) {
        if (infos[k].valid_data) {
          const std::uint32_t size = ddsi_serdata_size(samples[k]);
          std::vector<std::uint8_t> bytes(size);
          ddsi_serdata_to_ser(samples[k], 0, size, bytes.data());
          out.push_back(std::move(bytes));
        }
        ddsi_serdata_unref(samples[k]);
      }
    } catch (...) {  // Out of memory: the references taken are given back.
      for (; k < n; ++k) ddsi_serdata_unref(samples[k]);
      throw;
    }
    if (static_cast<std::uint32_t>(n) < kBatch) break;
  }
  return out;
}

Matches Reader::matches() const {
  Matches m;
  dds_subscription_matched_status_t matched{};
  dds_get_subscription_matched_status(reader_, &matched);
  m.current = static_cast<int>(matched.current_count);
  dds_requested_incompatible_qos_status_t incompatible{};
  dds_get_requested_incompatible_qos_status(reader_, &incompatible);
  m.incompatible = static_cast<int>(incompatible.total_count);
  m.last_incompatible_policy =
      policy_name(static_cast<dds_qos_policy_id_t>(incompatible.last_policy_id));
  return m;
}

std::array<std::uint8_t, 16> Reader::guid() const { return guid_of(reader_); }

}  // namespace dispel::ros2
