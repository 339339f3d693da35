// rosbag2's sqlite3 storage (storage.hpp) over Debian's libsqlite3: a .db3 file with tables
// topics and messages (every schema version, Foxy's topics without offered_qos_profiles too), and
// since Jazzy (schema version 4) schema, metadata, message_definitions and
// topics.type_description_hash. Written at schema version 4, as rosbag2's SqliteStorage of Jazzy
// writes it.

#include <sqlite3.h>

#include <cstring>
#include <map>
#include <set>

#include "dispel/io/errors.hpp"
#include "dispel/io/text.hpp"
#include "storage.hpp"

namespace dispel::io::rosbag2 {
namespace {

using Statement = std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)>;

// The tables as rosbag2 of Jazzy creates them (its schema version 4); the index on timestamp is
// added when the messages are in.
const char* const kCreate =
    "PRAGMA journal_mode = MEMORY; PRAGMA synchronous = OFF;"
    "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
    "CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL,"
    " metadata TEXT NOT NULL);"
    "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
    " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL,"
    " type_description_hash TEXT NOT NULL);"
    "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL,"
    " encoding TEXT NOT NULL, encoded_message_definition TEXT NOT NULL,"
    " type_description_hash TEXT NOT NULL);"
    "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,"
    " timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
    "INSERT INTO schema (schema_version, ros_distro) VALUES (4, 'jazzy');"
    "BEGIN TRANSACTION;";

std::uint64_t ns_of(sqlite3_int64 timestamp) {
  return timestamp < 0 ? 0 : static_cast<std::uint64_t>(timestamp);
}

std::string text(sqlite3_stmt* s, int column) {
  const unsigned char* p = sqlite3_column_text(s, column);
  return p == nullptr ? std::string()
                      : std::string(reinterpret_cast<const char*>(p),
                                    static_cast<std::size_t>(sqlite3_column_bytes(s, column)));
}

// A connection: read-only (errors InputError) or creating the file (errors OutputError), both
// naming @p name.
class Database {
 public:
  Database(const std::string& file, std::string name, bool writing)
      : name_(std::move(name)), writing_(writing) {
    sqlite3* db = nullptr;
    const int rc = sqlite3_open_v2(
        file.c_str(), &db,
        writing ? SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE : SQLITE_OPEN_READONLY, nullptr);
    db_.reset(db);
    if (rc != SQLITE_OK) {
      const int e = db == nullptr ? 0 : sqlite3_system_errno(db);
      fail(e != 0 ? std::strerror(e) : sqlite3_errstr(rc));
    }
    sqlite3_busy_timeout(db, 1000);  // A writer's transaction going on: wait for it a while.
    // A file's schema is outside data: no value longer than 256 MiB (a generated column of
    // zeroblob(900000000) is refused, not made), no functions with side effects in it, no
    // writes to the schema.
    sqlite3_limit(db, SQLITE_LIMIT_LENGTH, 256 << 20);
    sqlite3_db_config(db, SQLITE_DBCONFIG_TRUSTED_SCHEMA, 0, nullptr);
    sqlite3_db_config(db, SQLITE_DBCONFIG_DEFENSIVE, 1, nullptr);
  }

  [[noreturn]] void fail(const std::string& what) const {
    if (writing_) throw OutputError(one_line(name_ + ": cannot write (" + what + ")", 400));
    throw InputError(
        one_line(name_ + ": cannot read as a rosbag2 sqlite3 file (" + what + ")", 400));
  }
  void check(int rc) const {
    if (rc != SQLITE_OK && rc != SQLITE_ROW && rc != SQLITE_DONE) fail(sqlite3_errmsg(db_.get()));
  }

  void exec(const char* sql) const {
    check(sqlite3_exec(db_.get(), sql, nullptr, nullptr, nullptr));
  }
  Statement prepare(const std::string& sql) const {
    sqlite3_stmt* s = nullptr;
    check(sqlite3_prepare_v2(db_.get(), sql.c_str(), -1, &s, nullptr));
    return Statement(s, sqlite3_finalize);
  }
  /// true: a row; false: done.
  bool step(const Statement& s) const {
    const int rc = sqlite3_step(s.get());
    check(rc);
    return rc == SQLITE_ROW;
  }

  // Binding: the values are used before they change (no copy); an empty blob is not NULL.
  void bind(const Statement& s, int i, sqlite3_int64 v) const {
    check(sqlite3_bind_int64(s.get(), i, v));
  }
  void bind(const Statement& s, int i, const std::string& v) const {
    bind(s, i, v.data(), v.size(), true);
  }
  void bind(const Statement& s, int i, const void* data, std::size_t size, bool as_text) const {
    check(as_text ? sqlite3_bind_text64(s.get(), i, static_cast<const char*>(data), size, nullptr,
                                        SQLITE_UTF8)
                  : sqlite3_bind_blob64(s.get(), i, data != nullptr ? data : "", size, nullptr));
  }
  /// Runs @p s once with @p values bound, then resets it.
  template <typename... Values>
  void run(const Statement& s, const Values&... values) const {
    int i = 0;
    (bind(s, ++i, values), ...);
    step(s);
    check(sqlite3_reset(s.get()));
  }

  /// The first column of every row of @p sql.
  std::set<std::string> names(const std::string& sql) const {
    std::set<std::string> out;
    const Statement s = prepare(sql);
    while (step(s)) out.insert(text(s.get(), 0));
    return out;
  }

  sqlite3_int64 last_id() const { return sqlite3_last_insert_rowid(db_.get()); }
  void close() {
    check(sqlite3_close(db_.get()));
    (void)db_.release();
  }

 private:
  std::unique_ptr<sqlite3, int (*)(sqlite3*)> db_{nullptr, sqlite3_close_v2};
  std::string name_;
  bool writing_;
};

class Sqlite3Reader final : public StorageReader {
 public:
  explicit Sqlite3Reader(const std::string& path) : db_(path, path, false) {
    const std::set<std::string> tables =
        db_.names("SELECT name FROM sqlite_master WHERE type = 'table'");
    if (tables.count("topics") == 0 || tables.count("messages") == 0) {
      throw InputError(path +
                       ": an SQLite database without the tables topics and messages, not a "
                       "rosbag2 sqlite3 file");
    }
    const std::set<std::string> columns = db_.names("SELECT name FROM pragma_table_info('topics')");
    const bool qos = columns.count("offered_qos_profiles") != 0;
    const bool hash = columns.count("type_description_hash") != 0;
    std::map<std::string, std::pair<std::string, std::string>> definitions;  // By type.
    if (tables.count("message_definitions") != 0) {
      const Statement s = db_.prepare(
          "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions "
          "ORDER BY id");
      while (db_.step(s))
        definitions.emplace(text(s.get(), 0), std::pair(text(s.get(), 1), text(s.get(), 2)));
    }
    const Statement s =
        db_.prepare(std::string("SELECT id, name, type, serialization_format, ") +
                    (qos ? "offered_qos_profiles" : "''") + ", " +
                    (hash ? "type_description_hash" : "''") + " FROM topics ORDER BY id");
    while (db_.step(s)) {
      StoredTopic t{
          text(s.get(), 1), text(s.get(), 2), text(s.get(), 3), {}, "", {}, MessageKind::kOther, 0};
      if (qos) t.metadata.emplace_back("offered_qos_profiles", text(s.get(), 4));
      if (!text(s.get(), 5).empty()) t.metadata.emplace_back("topic_type_hash", text(s.get(), 5));
      const auto d = definitions.find(t.type);
      if (d != definitions.end() && !d->second.second.empty()) {
        t.definition_encoding = d->second.first;
        t.definition.assign(d->second.second.begin(), d->second.second.end());
      }
      index_[sqlite3_column_int64(s.get(), 0)] = topics_.size();
      topics_.push_back(std::move(t));
    }
    const Statement counts = db_.prepare(
        "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY "
        "topic_id");
    bool first = true;
    while (db_.step(counts)) {
      const auto t = index_.find(sqlite3_column_int64(counts.get(), 0));
      if (t == index_.end()) continue;  // Messages of no topic: never read.
      topics_[t->second].messages =
          static_cast<std::uint64_t>(sqlite3_column_int64(counts.get(), 1));
      const std::uint64_t b = ns_of(sqlite3_column_int64(counts.get(), 2));
      const std::uint64_t e = ns_of(sqlite3_column_int64(counts.get(), 3));
      if (first || b < start_ns_) start_ns_ = b;
      if (first || e > end_ns_) end_ns_ = e;
      first = false;
    }
  }

  // The order from the index on timestamp (rosbag2 creates it) without the bytes; then the bytes
  // of each message wanted, by its id.
  void read(const std::function<bool(std::size_t)>& wanted,
            const std::function<void(std::size_t, std::uint64_t, const std::uint8_t*, std::size_t)>&
                visit) override {
    const Statement order =
        db_.prepare("SELECT id, topic_id, timestamp FROM messages ORDER BY timestamp, id");
    const Statement data = db_.prepare("SELECT data FROM messages WHERE id = ?");
    while (db_.step(order)) {
      const auto t = index_.find(sqlite3_column_int64(order.get(), 1));
      if (t == index_.end() || !wanted(t->second)) continue;
      db_.check(sqlite3_reset(data.get()));
      db_.bind(data, 1, sqlite3_column_int64(order.get(), 0));
      if (!db_.step(data)) db_.fail("a message vanished while read");
      visit(t->second, ns_of(sqlite3_column_int64(order.get(), 2)),
            static_cast<const std::uint8_t*>(sqlite3_column_blob(data.get(), 0)),
            static_cast<std::size_t>(sqlite3_column_bytes(data.get(), 0)));
    }
  }

 private:
  Database db_;
  std::map<sqlite3_int64, std::size_t> index_;  // Topic id to topic index.
};

class Sqlite3Writer final : public StorageWriter {
 public:
  Sqlite3Writer(const std::string& file, const std::string& name) : db_(file, name, true) {
    db_.exec(kCreate);
    insert_ = db_.prepare("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)");
  }

  std::size_t add_topic(const StoredTopic& t) override {
    db_.run(db_.prepare("INSERT INTO topics (name, type, serialization_format, "
                        "offered_qos_profiles, type_description_hash) VALUES (?, ?, ?, ?, ?)"),
            t.name, t.type, t.serialization_format, value_of(t.metadata, "offered_qos_profiles"),
            value_of(t.metadata, "topic_type_hash"));
    ids_.push_back(db_.last_id());
    if (!t.definition.empty() && defined_.insert(t.type).second) {
      db_.run(db_.prepare("INSERT INTO message_definitions (topic_type, encoding, "
                          "encoded_message_definition, type_description_hash) VALUES (?, ?, ?, ?)"),
              t.type, t.definition_encoding, std::string(t.definition.begin(), t.definition.end()),
              value_of(t.metadata, "topic_type_hash"));
    }
    return ids_.size() - 1;
  }

  void write(std::size_t topic, std::uint64_t ns, const std::uint8_t* data,
             std::size_t size) override {
    db_.bind(insert_, 3, data, size, false);
    db_.run(insert_, ids_.at(topic), static_cast<sqlite3_int64>(ns));
  }

  void finish(const std::string& metadata, int metadata_version) override {
    db_.run(db_.prepare("INSERT INTO metadata (metadata_version, metadata) VALUES (?, ?)"),
            sqlite3_int64{metadata_version}, metadata);
    db_.exec("CREATE INDEX timestamp_idx ON messages (timestamp ASC); COMMIT;");
    insert_.reset();
    db_.close();
  }

 private:
  Database db_;
  Statement insert_{nullptr, sqlite3_finalize};
  std::vector<sqlite3_int64> ids_;  // By topic index.
  std::set<std::string> defined_;   // The types in message_definitions.
};

}  // namespace

std::unique_ptr<StorageReader> open_sqlite3(const std::string& path) {
  return std::make_unique<Sqlite3Reader>(path);
}

std::unique_ptr<StorageWriter> create_sqlite3(const std::string& file, const std::string& name) {
  return std::make_unique<Sqlite3Writer>(file, name);
}

}  // namespace dispel::io::rosbag2
