#include "dispel/io/rosbag2.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>

#include "dispel/io/errors.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "mcap.hpp"

namespace dispel::io {
namespace {

namespace fs = std::filesystem;

class Rosbag2 : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("dispel_rosbag2_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string at(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

// How many entries of the folder of @p prefix have names that begin as it does.
int entries_starting(const std::string& prefix) {
  const fs::path p(prefix);
  int n = 0;
  for (const auto& e : fs::directory_iterator(p.parent_path())) {
    if (e.path().filename().string().rfind(p.filename().string(), 0) == 0) ++n;
  }
  return n;
}

ScanMessage scan_at(int i) {
  ScanMessage m;
  m.header.stamp = {1700000000 + i / 10, static_cast<std::uint32_t>((i % 10) * 100000000)};
  m.header.frame_id = "laser";
  m.scan.stamp_s = m.header.stamp.seconds();
  m.scan.angle_min_rad = -1.0;
  m.scan.angle_increment_rad = 0.01;
  m.scan.range_min_m = 0.1F;
  m.scan.range_max_m = 20.0F;
  for (int b = 0; b < 200; ++b) m.scan.ranges_m.push_back(1.0F + 0.01F * static_cast<float>(b + i));
  m.angle_max = -1.0F + 0.01F * 199;
  return m;
}

// Writes 300 scans, odometry between them and one static transform.
void write_recording(RecordingWriter& w) {
  TransformsMessage tf;
  tf.transforms.push_back({{1700000000, 0}, "base_link", "laser", {0.2, -0.1, 0.3}});
  w.write("/tf_static", {1700000000, 0}, tf);
  for (int i = 0; i < 300; ++i) {
    const ScanMessage s = scan_at(i);
    w.write("/scan", s.header.stamp, s);
    const OdometryMessage o =
        odometry_message(s.header.stamp.seconds() + 0.05, "odom", "base_link", {0.01 * i, 0, 0});
    w.write("/odom", o.header.stamp, o);
  }
  w.finish();
}

std::string text_of(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream text;
  text << f.rdbuf();
  return text.str();
}

std::vector<std::pair<std::string, Stamp>> messages_of(RecordingReader& r) {
  std::vector<std::pair<std::string, Stamp>> out;
  r.read({}, [&](const RecordedMessage& m) { out.emplace_back(m.topic(), m.time()); });
  return out;
}

TEST_F(Rosbag2, WhatIsWrittenIsReadBackInEveryCompressionAndLayout) {
  const Rosbag2Storage mcap = Rosbag2Storage::kMcap;
  const Rosbag2Storage sqlite3 = Rosbag2Storage::kSqlite3;
  for (const auto& [name, c, storage] :
       std::vector<std::tuple<std::string, Rosbag2Compression, Rosbag2Storage>>{
           {"plain.mcap", Rosbag2Compression::kNone, mcap},
           {"zstd.mcap", Rosbag2Compression::kZstd, mcap},
           {"lz4.mcap", Rosbag2Compression::kLz4, mcap},
           {"folder", Rosbag2Compression::kZstd, mcap},
           {"plain.db3", Rosbag2Compression::kNone, mcap},  // .db3: sqlite3 whatever is asked.
           {"sqlite_folder", Rosbag2Compression::kNone, sqlite3}}) {
    SCOPED_TRACE(name);
    {
      Rosbag2Writer w(at(name), c, storage);
      write_recording(w);
      EXPECT_EQ(w.messages_written(), 601);
    }
    EXPECT_EQ(entries_starting(at(name) + ".partial"), 0);
    Rosbag2Reader r(at(name));
    const bool db3 = name == "plain.db3" || name == "sqlite_folder";
    EXPECT_EQ(r.format_name(), db3 ? "rosbag2 (sqlite3)" : "rosbag2 (mcap)");
    EXPECT_EQ(r.topics().messages("/scan"), 300);
    EXPECT_EQ(r.topics().messages("/odom"), 300);
    EXPECT_TRUE(r.topics().has("/tf_static", MessageKind::kTransforms));
    EXPECT_EQ(r.topics().all().at("/scan").type, "sensor_msgs/msg/LaserScan");
    EXPECT_EQ(r.begin_time(), (Stamp{1700000000, 0}));
    EXPECT_NEAR(r.end_time().seconds(), 1700000029.95, 1e-6);  // The last odometry.
    const auto all = messages_of(r);
    ASSERT_EQ(all.size(), 601U);
    for (std::size_t i = 1; i < all.size(); ++i) EXPECT_FALSE(all[i].second < all[i - 1].second);
    int scans = 0;
    r.read({"/scan"}, [&](const RecordedMessage& m) {
      const auto s = m.scan();
      ASSERT_TRUE(s.has_value());
      const ScanMessage e = scan_at(scans);
      EXPECT_EQ(s->header.stamp, e.header.stamp);
      EXPECT_EQ(s->scan.ranges_m, e.scan.ranges_m);
      EXPECT_FALSE(m.odometry().has_value());
      ++scans;
    });
    EXPECT_EQ(scans, 300);
  }
  EXPECT_TRUE(fs::exists(at("folder") + "/metadata.yaml"));
  EXPECT_TRUE(fs::exists(at("folder") + "/folder_0.mcap"));
  EXPECT_TRUE(fs::exists(at("sqlite_folder") + "/sqlite_folder_0.db3"));
  EXPECT_NE(text_of(at("sqlite_folder") + "/metadata.yaml").find("storage_identifier: sqlite3"),
            std::string::npos);
}

TEST_F(Rosbag2, ACopyKeepsTheBytesTheTypeAndTheQos) {
  {
    Rosbag2Writer w(at("in.mcap"), Rosbag2Compression::kNone);
    write_recording(w);
  }
  Rosbag2Reader in(at("in.mcap"));
  {
    Rosbag2Writer out(at("out"), Rosbag2Compression::kLz4);
    in.read({}, [&](const RecordedMessage& m) { out.copy(m); });
    out.finish();
  }
  Rosbag2Reader back(at("out"));
  ASSERT_EQ(back.topics().all().size(), in.topics().all().size());
  for (const auto& [name, t] : in.topics().all()) {
    EXPECT_EQ(back.topics().all().at(name).type, t.type);
    EXPECT_EQ(back.topics().all().at(name).kind, t.kind);
    EXPECT_EQ(back.topics().all().at(name).messages, t.messages);
  }
  std::vector<std::vector<std::uint8_t>> a, b;
  in.read({"/scan"}, [&](const RecordedMessage& m) { a.push_back(encode_ros2(*m.scan())); });
  back.read({"/scan"}, [&](const RecordedMessage& m) { b.push_back(encode_ros2(*m.scan())); });
  EXPECT_EQ(a, b);
  const std::string text = text_of(at("out") + "/metadata.yaml");
  EXPECT_NE(text.find("storage_identifier: mcap"), std::string::npos) << text;
  EXPECT_NE(text.find("durability: 1"), std::string::npos) << "/tf_static is transient local";
}

std::vector<char> bytes_of(const std::string& path) {
  const std::string text = text_of(path);
  return {text.begin(), text.end()};
}
void put(const std::string& path, const std::vector<char>& b) {
  std::ofstream f(path, std::ios::binary);
  f.write(b.data(), static_cast<std::streamsize>(b.size()));
}
void put_text(const std::string& path, const std::string& text) {
  put(path, std::vector<char>(text.begin(), text.end()));
}

std::string error_of(const std::string& path) {
  try {
    Rosbag2Reader r(path);
    r.read({}, [](const RecordedMessage& m) { (void)m.scan(); });
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST_F(Rosbag2, ACorruptOrCutFileIsOneLineNamingTheProblem) {
  {
    Rosbag2Writer w(at("good.mcap"), Rosbag2Compression::kZstd);
    write_recording(w);
  }
  const std::vector<char> good = bytes_of(at("good.mcap"));
  std::vector<char> b = good;
  b[1] = 'X';
  put(at("magic.mcap"), b);
  EXPECT_NE(error_of(at("magic.mcap")).find("not an MCAP file"), std::string::npos);
  put(at("cut.mcap"),
      std::vector<char>(good.begin(), good.begin() + static_cast<long>(good.size() / 2)));
  EXPECT_NE(error_of(at("cut.mcap")).find("truncated"), std::string::npos);
  // Every single flipped byte: an error or a good read, never a crash (the sanitizers watch).
  int errors = 0;
  for (std::size_t i = 8; i < good.size(); i += 97) {
    b = good;
    b[i] = static_cast<char>(b[i] ^ 0x5a);
    put(at("flip.mcap"), b);
    const std::string e = error_of(at("flip.mcap"));
    if (!e.empty()) {
      ++errors;
      EXPECT_EQ(e.find('\n'), std::string::npos) << e;
      EXPECT_LE(e.size(), 500U) << e;
      EXPECT_EQ(e.rfind(at("flip.mcap"), 0), 0U) << e;
    }
  }
  EXPECT_GT(errors, 0);
  // A byte of a message changed in an uncompressed file (the middle of the file is inside its
  // one chunk): the chunk's CRC says so when the chunk is read.
  {
    Rosbag2Writer w(at("plain.mcap"), Rosbag2Compression::kNone);
    write_recording(w);
  }
  b = bytes_of(at("plain.mcap"));
  b[b.size() / 2] = static_cast<char>(b[b.size() / 2] ^ 0x01);
  put(at("crc.mcap"), b);
  EXPECT_NE(error_of(at("crc.mcap")).find("a chunk's CRC does not match"), std::string::npos)
      << error_of(at("crc.mcap"));
  fs::create_directories(at("nometa"));
  EXPECT_NE(error_of(at("nometa")).find("without metadata.yaml"), std::string::npos);
  fs::create_directories(at("foo"));
  put_text(at("foo/metadata.yaml"),
           "rosbag2_bagfile_information:\n  storage_identifier: foo\n"
           "  relative_file_paths: [x.foo]\n");
  EXPECT_NE(error_of(at("foo")).find("storage 'foo'"), std::string::npos) << error_of(at("foo"));
}

TEST_F(Rosbag2, AFolderThatExistsIsNeverReplacedAndAnUnfinishedOneLeavesNothing) {
  fs::create_directories(at("there"));
  EXPECT_THROW(Rosbag2Writer(at("there"), Rosbag2Compression::kNone), OutputError);
  {
    Rosbag2Writer w(at("unfinished"), Rosbag2Compression::kNone);
    w.write("/scan", {1, 0}, scan_at(0));
  }
  EXPECT_FALSE(fs::exists(at("unfinished")));
  EXPECT_EQ(entries_starting(at("unfinished.partial")), 0);
}

// ---------------------------------------------------------------------------------------------
// sqlite3 storage

// Runs a Python 3 script (Debian's python3 and its sqlite3 module: independent of dispel's
// writer) with @p args; what it prints, errors included.
std::string python(const fs::path& dir, const std::string& script, const std::string& args) {
  const std::string file = (dir / "script.py").string();
  put_text(file, script);
  std::FILE* p = ::popen(("/usr/bin/python3 " + file + " " + args + " 2>&1").c_str(), "r");
  if (p == nullptr) return "cannot run python3";
  std::string out;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, p)) > 0;) out.append(buffer, n);
  ::pclose(p);
  return out;
}

std::string hex_of(const std::vector<std::uint8_t>& bytes) {
  std::string out;
  for (const std::uint8_t b : bytes)
    out += "0123456789abcdef"[b >> 4], out += "0123456789abcdef"[b & 15];
  return out;
}

TEST_F(Rosbag2, ACopyFromMcapToSqlite3AndBackKeepsTheBytes) {
  {
    Rosbag2Writer w(at("in.mcap"), Rosbag2Compression::kNone);
    write_recording(w);
  }
  const auto copy = [](const std::string& from, const std::string& to, Rosbag2Storage storage) {
    Rosbag2Reader in(from);
    Rosbag2Writer out(to, Rosbag2Compression::kNone, storage);
    in.read({}, [&](const RecordedMessage& m) {
      EXPECT_TRUE(out.can_copy(m));
      out.copy(m);
    });
    out.finish();
    EXPECT_EQ(out.messages_written(), 601);
  };
  copy(at("in.mcap"), at("copy.db3"), Rosbag2Storage::kMcap);
  copy(at("copy.db3"), at("folder"), Rosbag2Storage::kSqlite3);
  copy(at("folder"), at("back.mcap"), Rosbag2Storage::kMcap);
  // The same channels, schemas (type definitions), QoS and message bytes: the same file.
  EXPECT_EQ(bytes_of(at("back.mcap")), bytes_of(at("in.mcap")));
  Rosbag2Reader in(at("in.mcap"));
  Rosbag2Reader folder(at("folder"));
  EXPECT_EQ(folder.format_name(), "rosbag2 (sqlite3)");
  for (const auto& [name, t] : in.topics().all()) {
    EXPECT_EQ(folder.topics().all().at(name).type, t.type);
    EXPECT_EQ(folder.topics().all().at(name).kind, t.kind);
    EXPECT_EQ(folder.topics().all().at(name).messages, t.messages);
  }
  EXPECT_NE(text_of(at("folder/metadata.yaml")).find("durability: 1"), std::string::npos);
}

TEST_F(Rosbag2, ADb3OfDispelIsReadByPythonsSqlite3) {
  {
    Rosbag2Writer w(at("out.db3"), Rosbag2Compression::kNone);
    write_recording(w);
  }
  const std::string script = R"py(import sqlite3, sys
db = sqlite3.connect("file:" + sys.argv[1] + "?mode=ro", uri=True)
print(db.execute("PRAGMA integrity_check").fetchone()[0])
print(sorted(r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")))
print(db.execute("SELECT schema_version, ros_distro FROM schema").fetchall())
for name, n in db.execute("SELECT topics.name, COUNT(*) FROM messages JOIN topics"
                          " ON topics.id = messages.topic_id GROUP BY topics.name ORDER BY 1"):
    print(name, n)
print(db.execute("SELECT data FROM messages JOIN topics ON topics.id = topic_id WHERE"
                 " topics.name = '/scan' ORDER BY timestamp, messages.id").fetchone()[0].hex())
print(db.execute("SELECT topic_type, encoding FROM message_definitions ORDER BY id").fetchall())
print(db.execute("SELECT offered_qos_profiles FROM topics WHERE name = '/tf_static'")
      .fetchone()[0].count("durability: 1"))
print(db.execute("SELECT metadata_version, instr(metadata, 'storage_identifier: sqlite3') > 0"
                 " FROM metadata").fetchall())
print(db.execute("SELECT name FROM sqlite_master WHERE type = 'index'").fetchall())
)py";
  EXPECT_EQ(python(dir_, script, at("out.db3")),
            "ok\n"
            "['message_definitions', 'messages', 'metadata', 'schema', 'topics']\n"
            "[(4, 'jazzy')]\n"
            "/odom 300\n/scan 300\n/tf_static 1\n" +
                hex_of(encode_ros2(scan_at(0))) +
                "\n"
                "[('tf2_msgs/msg/TFMessage', 'ros2msg'), ('sensor_msgs/msg/LaserScan', 'ros2msg'), "
                "('nav_msgs/msg/Odometry', 'ros2msg')]\n"
                "1\n"
                "[(5, 1)]\n"
                "[('timestamp_idx',)]\n");
}

// Writes <layout>.db3 as rosbag2 of that release lays it out: topics without
// offered_qos_profiles (foxy), with it (humble), with type_description_hash and the tables
// schema, metadata and message_definitions (jazzy). Messages inserted last first, topic ids
// 7, 9, 12 and 13 (without messages).
const char* const kLayouts = R"py(import sqlite3, sys
path, layout, folder = sys.argv[1:4]
db = sqlite3.connect(path)
columns = "id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL"
if layout != "foxy":
    columns += ", offered_qos_profiles TEXT NOT NULL"
if layout == "jazzy":
    columns += ", type_description_hash TEXT NOT NULL"
    db.execute("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL)")
    db.execute("INSERT INTO schema VALUES (4, 'jazzy')")
    db.execute("CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL,"
               " metadata TEXT NOT NULL)")
    db.execute("CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL,"
               " encoding TEXT NOT NULL, encoded_message_definition TEXT NOT NULL,"
               " type_description_hash TEXT NOT NULL)")
    db.execute("INSERT INTO message_definitions (topic_type, encoding, encoded_message_definition,"
               " type_description_hash) VALUES ('sensor_msgs/msg/LaserScan', 'ros2msg',"
               " '# LaserScan as Jazzy keeps it', 'RIHS01_5ca1')")
db.execute("CREATE TABLE topics(" + columns + ")")
db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,"
           " timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
db.execute("CREATE INDEX timestamp_idx ON messages (timestamp ASC)")
for id, name, type in ((7, "/scan", "sensor_msgs/msg/LaserScan"), (9, "/odom", "nav_msgs/msg/Odometry"),
                       (12, "/chatter", "std_msgs/msg/String"), (13, "/empty", "std_msgs/msg/Empty")):
    values = [id, name, type, "cdr"]
    if layout != "foxy":
        values.append("- history: 1\n  depth: 7\n  reliability: 2\n  durability: 2")
    if layout == "jazzy":
        values.append("RIHS01_5ca1" if id == 7 else "")
    db.execute("INSERT INTO topics VALUES (" + ", ".join("?" * len(values)) + ")", values)
t0 = 1700000000 * 10**9
rows = [(12, t0 + 20000000, b"\0\1\0\0\3\0\0\0hi\0"), (12, t0 + 30000000, b"\0\1\0\0\1\0\0\0\0")]
for i in range(5):
    rows.append((7, t0 + i * 100000000, open(f"{folder}/scan{i}.bin", "rb").read()))
    rows.append((9, t0 + i * 100000000 + 50000000, open(f"{folder}/odom{i}.bin", "rb").read()))
for r in reversed(rows):
    db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)", r)
db.commit()
)py";

OdometryMessage odometry_at(int i) {
  return odometry_message(1700000000.05 + 0.1 * i, "odom", "base_link", {0.1 * i, 0, 0});
}

TEST_F(Rosbag2, Db3FilesOfFoxyHumbleAndJazzyAreRead) {
  for (int i = 0; i < 5; ++i) {
    const std::vector<std::uint8_t> s = encode_ros2(scan_at(i));
    const std::vector<std::uint8_t> o = encode_ros2(odometry_at(i));
    put_text(at("scan" + std::to_string(i) + ".bin"), std::string(s.begin(), s.end()));
    put_text(at("odom" + std::to_string(i) + ".bin"), std::string(o.begin(), o.end()));
  }
  for (const std::string layout : {"foxy", "humble", "jazzy"}) {
    SCOPED_TRACE(layout);
    const std::string db3 = at(layout + ".db3");
    ASSERT_EQ(python(dir_, kLayouts, db3 + " " + layout + " " + dir_.string()), "");
    Rosbag2Reader r(db3);
    EXPECT_EQ(r.format_name(), "rosbag2 (sqlite3)");
    EXPECT_TRUE(r.topics().has("/scan", MessageKind::kLaserScan));
    EXPECT_TRUE(r.topics().has("/odom", MessageKind::kOdometry));
    EXPECT_EQ(r.topics().messages("/scan"), 5);
    EXPECT_EQ(r.topics().messages("/odom"), 5);
    EXPECT_EQ(r.topics().messages("/chatter"), 2);
    EXPECT_EQ(r.topics().messages("/empty"), 0);
    EXPECT_EQ(r.topics().all().at("/chatter").type, "std_msgs/msg/String");
    EXPECT_EQ(r.topics().all().at("/chatter").kind, MessageKind::kOther);
    EXPECT_EQ(r.begin_time(), (Stamp{1700000000, 0}));
    EXPECT_EQ(r.end_time(), (Stamp{1700000000, 450000000}));
    const auto all = messages_of(r);
    ASSERT_EQ(all.size(), 12U);
    for (std::size_t i = 1; i < all.size(); ++i) EXPECT_FALSE(all[i].second < all[i - 1].second);
    EXPECT_EQ(all[1].first, "/chatter");
    int scans = 0;
    int odometry = 0;
    r.read({"/scan", "/odom"}, [&](const RecordedMessage& m) {
      if (const auto s = m.scan()) {
        EXPECT_EQ(s->scan.ranges_m, scan_at(scans++).scan.ranges_m);
      } else {
        EXPECT_EQ(m.odometry()->header.stamp, odometry_at(odometry++).header.stamp);
      }
    });
    EXPECT_EQ(scans, 5);
    EXPECT_EQ(odometry, 5);
    // Copied into MCAP: the definition the file holds (else dispel's own) and the QoS.
    {
      Rosbag2Writer out(at(layout + ".mcap"), Rosbag2Compression::kNone);
      r.read({}, [&](const RecordedMessage& m) { out.copy(m); });
      out.finish();
      EXPECT_EQ(out.messages_written(), 12);
    }
    mcap::Reader copy(at(layout + ".mcap"));
    for (const auto& [id, c] : copy.channels()) {
      if (c.topic != "/scan") continue;
      const mcap::Schema& s = copy.schemas().at(c.schema_id);
      EXPECT_EQ(std::string(s.data.begin(), s.data.end()),
                layout == "jazzy" ? "# LaserScan as Jazzy keeps it"
                                  : ros2_definition(MessageKind::kLaserScan));
      using Metadata = std::vector<std::pair<std::string, std::string>>;
      const Metadata qos = {
          {"offered_qos_profiles", "- history: 1\n  depth: 7\n  reliability: 2\n  durability: 2"}};
      EXPECT_EQ(c.metadata,
                (layout == "foxy"     ? Metadata()
                 : layout == "humble" ? qos
                                      : Metadata{qos[0], {"topic_type_hash", "RIHS01_5ca1"}}));
    }
    EXPECT_EQ(Rosbag2Reader(at(layout + ".mcap")).topics().messages("/chatter"), 2);
  }
}

TEST_F(Rosbag2, ACorruptLockedOrForeignDb3IsOneLineNamingTheFile) {
  {
    Rosbag2Writer w(at("good.db3"), Rosbag2Compression::kNone);
    write_recording(w);
  }
  const std::string good = text_of(at("good.db3"));
  put_text(at("cut.db3"), good.substr(0, good.size() / 2));
  put_text(at("text.db3"), "a text file, not a database\n");
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open(at("other.db3").c_str(), &other), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(other, "CREATE TABLE foo(x INTEGER)", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(other);
  put_text(at("locked.db3"), good);
  sqlite3* locker = nullptr;
  ASSERT_EQ(sqlite3_open(at("locked.db3").c_str(), &locker), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(locker, "BEGIN EXCLUSIVE", nullptr, nullptr, nullptr), SQLITE_OK);
  for (const auto& [name, problem] : std::vector<std::pair<std::string, std::string>>{
           {"cut.db3", "malformed"},
           {"text.db3", "not a database"},
           {"other.db3", "without the tables topics and messages"},
           {"locked.db3", "database is locked"},
           {"missing.db3", "No such file"}}) {
    const std::string e = error_of(at(name));
    EXPECT_NE(e.find(problem), std::string::npos) << e;
    EXPECT_EQ(e.rfind(at(name) + ": ", 0), 0U) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  sqlite3_exec(locker, "ROLLBACK", nullptr, nullptr, nullptr);
  sqlite3_close(locker);
  EXPECT_EQ(error_of(at("locked.db3")), "");
  // Flipped bytes: an error naming the file or a good read, never a crash.
  for (std::size_t i = 0; i < good.size(); i += 9973) {
    std::string b = good;
    b[i] = static_cast<char>(b[i] ^ 0x5a);
    put_text(at("flip.db3"), b);
    const std::string e = error_of(at("flip.db3"));
    if (!e.empty()) {
      EXPECT_EQ(e.find('\n'), std::string::npos) << e;
      EXPECT_EQ(e.rfind(at("flip.db3"), 0), 0U) << e;
    }
  }
}

TEST_F(Rosbag2, Sqlite3IsNeverCompressedAndAnUnfinishedOneLeavesNothing) {
  for (const auto& [name, c] : std::vector<std::pair<std::string, Rosbag2Compression>>{
           {"zstd.db3", Rosbag2Compression::kZstd}, {"lz4", Rosbag2Compression::kLz4}}) {
    try {
      Rosbag2Writer w(at(name), c, Rosbag2Storage::kSqlite3);
      ADD_FAILURE() << name << " written compressed";
    } catch (const OutputError& e) {
      EXPECT_NE(std::string(e.what()).find("sqlite3 storage is not compressed"), std::string::npos)
          << e.what();
      EXPECT_EQ(std::string(e.what()).rfind(at(name) + ": cannot write (", 0), 0U) << e.what();
    }
  }
  EXPECT_THROW(Rosbag2Writer(at("no/such/folder.db3"), Rosbag2Compression::kNone), OutputError);
  {
    Rosbag2Writer file(at("unfinished.db3"), Rosbag2Compression::kNone);
    Rosbag2Writer folder(at("unfinished"), Rosbag2Compression::kNone, Rosbag2Storage::kSqlite3);
    file.write("/scan", {1, 0}, scan_at(0));
    folder.write("/scan", {1, 0}, scan_at(0));
    EXPECT_TRUE(fs::exists(at("unfinished.db3.partial")));
  }
  EXPECT_TRUE(fs::is_empty(dir_)) << "nothing left, no journal either";
}

}  // namespace
}  // namespace dispel::io

namespace dispel::io {
namespace {

// A bag folder as Jazzy's rosbag2 writes it (metadata version 9: QoS as a YAML list, custom_data,
// ros_distro), split over two files: both are read, one after the other.
TEST_F(Rosbag2, AJazzyBagFolderSplitOverTwoFilesIsReadWhole) {
  const auto write_part = [&](const std::string& name, int first) {
    Rosbag2Writer w(at(name), Rosbag2Compression::kZstd);
    for (int i = first; i < first + 50; ++i) w.write("/scan", scan_at(i).header.stamp, scan_at(i));
    w.finish();
  };
  write_part("part_0.mcap", 0);
  write_part("part_1.mcap", 50);
  fs::create_directories(at("jazzy"));
  fs::rename(at("part_0.mcap"), at("jazzy/part_0.mcap"));
  fs::rename(at("part_1.mcap"), at("jazzy/part_1.mcap"));
  const std::string metadata = R"(rosbag2_bagfile_information:
  version: 9
  storage_identifier: mcap
  duration:
    nanoseconds: 9900000000
  starting_time:
    nanoseconds_since_epoch: 1700000000000000000
  message_count: 100
  topics_with_message_count:
    - topic_metadata:
        name: /scan
        type: sensor_msgs/msg/LaserScan
        serialization_format: cdr
        offered_qos_profiles:
          - history: keep_last
            depth: 10
            reliability: best_effort
            durability: volatile
            deadline:
              sec: 9223372036
              nsec: 854775807
            lifespan:
              sec: 9223372036
              nsec: 854775807
            liveliness: automatic
            liveliness_lease_duration:
              sec: 9223372036
              nsec: 854775807
            avoid_ros_namespace_conventions: false
        type_description_hash: RIHS01_64ae8ee3ae8ab8b3e9a1d7f2c5f1b7ae2b1b6b2c8a3d5e6f7a8b9c0d1e2f3a4b
      message_count: 100
  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - part_0.mcap
    - part_1.mcap
  files:
    - path: part_0.mcap
      starting_time:
        nanoseconds_since_epoch: 1700000000000000000
      duration:
        nanoseconds: 4900000000
      message_count: 50
    - path: part_1.mcap
      starting_time:
        nanoseconds_since_epoch: 1700000005000000000
      duration:
        nanoseconds: 4900000000
      message_count: 50
  custom_data: ~
  ros_distro: jazzy
)";
  put(at("jazzy/metadata.yaml"), std::vector<char>(metadata.begin(), metadata.end()));
  Rosbag2Reader r(at("jazzy"));
  EXPECT_EQ(r.topics().messages("/scan"), 100);
  EXPECT_EQ(r.begin_time(), scan_at(0).header.stamp);
  EXPECT_EQ(r.end_time(), scan_at(99).header.stamp);
  int n = 0;
  r.read({}, [&](const RecordedMessage& m) {
    EXPECT_EQ(m.scan()->header.stamp, scan_at(n).header.stamp);
    ++n;
  });
  EXPECT_EQ(n, 100);
  // A file named outside the folder is refused.
  std::string escaping = metadata;
  escaping.replace(escaping.find("    - part_1.mcap"), 17, "    - ../part_1.mcap");
  put(at("jazzy/metadata.yaml"), std::vector<char>(escaping.begin(), escaping.end()));
  EXPECT_NE(error_of(at("jazzy")).find("not a name inside the bag folder"), std::string::npos)
      << error_of(at("jazzy"));
}

}  // namespace
}  // namespace dispel::io

namespace dispel::io {
namespace {

std::size_t open_files() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator("/proc/self/fd")) ++n;
  return n;
}

// Found by the fuzz target: a file refused while it was being opened kept its descriptor, and
// after some 20000 refusals nothing more could be opened.
TEST_F(Rosbag2, ARefusedFileLeavesNoDescriptorOpen) {
  {
    Rosbag2Writer w(at("good.mcap"), Rosbag2Compression::kNone);
    write_recording(w);
  }
  std::vector<char> b = bytes_of(at("good.mcap"));
  put(at("cut.mcap"), std::vector<char>(b.begin(), b.begin() + static_cast<long>(b.size() / 2)));
  b[b.size() - 30] = 'x';  // The footer.
  put(at("footer.mcap"), b);
  const std::size_t before = open_files();
  for (int i = 0; i < 50; ++i) {
    EXPECT_FALSE(error_of(at("cut.mcap")).empty());
    EXPECT_FALSE(error_of(at("footer.mcap")).empty());
    EXPECT_FALSE(error_of(at("missing.mcap")).empty());
  }
  EXPECT_EQ(open_files(), before);
}

}  // namespace
}  // namespace dispel::io

namespace dispel::io {
namespace {

// From the review of the first version: a writer never removes what it did not make, and a
// file that states sizes it cannot hold is refused before anything is allocated or looped over.
TEST_F(Rosbag2, AWriterRemovesNothingItDidNotMake) {
  fs::create_directories(at("keep.partial/notes"));
  put(at("keep.partial/notes/a.txt"), {'a'});
  {
    Rosbag2Writer w(at("keep"), Rosbag2Compression::kNone);
    write_recording(w);
  }
  EXPECT_TRUE(fs::exists(at("keep.partial/notes/a.txt")));
  EXPECT_TRUE(fs::exists(at("keep/metadata.yaml")));
  EXPECT_EQ(fs::status(at("keep")).permissions() & fs::perms::others_read, fs::perms::others_read);
}

TEST_F(Rosbag2, SizesAFileCannotHoldAreRefusedAtOnce) {
  {
    Rosbag2Writer w(at("small.mcap"), Rosbag2Compression::kZstd);
    write_recording(w);
  }
  // 84 bytes (from the review): magic, header, then 8 bytes before the summary that start a
  // record of 2^64 - 9 bytes; a summary without statistics, so the data section is walked.
  // Before the fix the walk wrapped around and never ended.
  std::string f("\x89MCAP0\r\n", 8);
  const auto u32 = [&](std::uint32_t v) { f.append(reinterpret_cast<const char*>(&v), 4); };
  const auto u64 = [&](std::uint64_t v) { f.append(reinterpret_cast<const char*>(&v), 8); };
  f += '\x01';
  u64(4 + 4 + 4 + 1);
  u32(4);
  f += "ros2";
  u32(1);
  f += 'x';
  f += std::string("\x07\xf7\xff\xff\xff\xff\xff\xff", 8);
  const std::uint64_t summary_start = f.size();
  f += std::string("\xff\0\0\0\0\0\0\0\0", 9);
  f += '\x02';
  u64(20);
  u64(summary_start);
  u64(0);
  u32(0);
  f += std::string("\x89MCAP0\r\n", 8);
  put(at("loop.mcap"), std::vector<char>(f.begin(), f.end()));
  EXPECT_NE(error_of(at("loop.mcap")).find("corrupt MCAP file"), std::string::npos)
      << error_of(at("loop.mcap"));
}

}  // namespace
}  // namespace dispel::io
