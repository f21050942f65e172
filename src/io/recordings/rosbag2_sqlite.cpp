// rosbag2's SQLite3 storage: a folder with metadata.yaml and one .db3 file per split, or a .db3 on its own.
// Each file has tables topics(id, name, type, serialization_format, offered_qos_profiles) and
// messages(id, topic_id, timestamp, data); read through Debian's libsqlite3, read-only.
#include "io/recordings/openers.h"

#include <sqlite3.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <mutex>
#include <tuple>

namespace vkmesh::io::recording {

namespace fs = std::filesystem;

namespace {

std::string trim(std::string s) {
    const char* ws = " \t\r\n";
    s.erase(0, s.find_first_not_of(ws));
    s.erase(s.find_last_not_of(ws) + 1);
    if (s.size() >= 2 && (s.front() == '\'' || s.front() == '"') && s.back() == s.front()) s = s.substr(1, s.size() - 2);
    return s;
}

// Name order with digit runs compared as numbers, so that b_10.db3 follows b_9.db3.
bool naturalLess(const std::string& a, const std::string& b) {
    size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
        if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
            size_t i2 = i, j2 = j;
            while (i2 < a.size() && std::isdigit(static_cast<unsigned char>(a[i2]))) ++i2;
            while (j2 < b.size() && std::isdigit(static_cast<unsigned char>(b[j2]))) ++j2;
            std::string x = a.substr(i, i2 - i), y = b.substr(j, j2 - j);
            x.erase(0, std::min(x.find_first_not_of('0'), x.size()));
            y.erase(0, std::min(y.find_first_not_of('0'), y.size()));
            if (x.size() != y.size()) return x.size() < y.size();
            if (x != y) return x < y;
            i = i2;
            j = j2;
        } else {
            if (a[i] != b[j]) return a[i] < b[j];
            ++i;
            ++j;
        }
    }
    return a.size() - i < b.size() - j;
}

// The file URI SQLite opens: read-only and immutable (no journal or -shm file is looked for or created, so a
// recording on a read-only medium opens too). Characters with a meaning in URIs are percent-encoded.
std::string fileUri(const fs::path& path) {
    std::error_code ec;
    fs::path absolute = fs::absolute(path, ec);
    std::string abs = (ec ? path : absolute).string(), uri = "file:";
    for (unsigned char c : abs) {
        if (std::isalnum(c) || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') {
            uri += static_cast<char>(c);
        } else {
            const char* d = "0123456789ABCDEF";
            uri += '%';
            uri += d[c >> 4];
            uri += d[c & 15];
        }
    }
    return uri + "?mode=ro&immutable=1";
}

class Rosbag2Sqlite final : public Container {
public:
    Rosbag2Sqlite(const fs::path& path, const std::vector<fs::path>& files) {
        path_ = path;
        if (files.empty()) throw Error(path.string() + ": a rosbag2 recording without any .db3 file");
        std::map<std::tuple<std::string, std::string, std::string>, uint32_t> merged;
        for (size_t f = 0; f < files.size(); ++f) {
            files_.push_back(std::make_unique<File>());
            File& file = *files_.back();
            file.path = files[f];
            const std::string name = file.path.string();
            if (sqlite3_open_v2(fileUri(file.path).c_str(), &file.db,
                                SQLITE_OPEN_READONLY | SQLITE_OPEN_URI | SQLITE_OPEN_NOMUTEX, nullptr) != SQLITE_OK)
                fail(file, "cannot open");
            // topic id (per file: a split bag's files number their topics each on their own) -> Connection.
            std::map<int64_t, uint32_t> topics;
            {
                Statement st(file, "SELECT id, name, type, serialization_format FROM topics");
                while (st.step()) {
                    std::string topic = text(st.s, 1), type = text(st.s, 2), format = text(st.s, 3);
                    std::string norm = detail::normaliseRosType(type);
                    auto [it, added] = merged.emplace(std::make_tuple(topic, norm, format), uint32_t(connections_.size()));
                    if (added) {
                        Connection c;
                        c.id = uint32_t(connections_.size());
                        c.topic = topic;
                        c.type = norm;
                        c.encoding = format;
                        c.serialization = format == "ros1" ? Serialization::Ros1 : Serialization::Cdr;
                        connections_.push_back(std::move(c));
                    }
                    topics[sqlite3_column_int64(st.s, 0)] = it->second;
                }
            }
            Statement st(file, "SELECT id, topic_id, timestamp FROM messages ORDER BY id");
            while (st.step()) {
                int64_t id = sqlite3_column_int64(st.s, 0), topic = sqlite3_column_int64(st.s, 1),
                        t = sqlite3_column_int64(st.s, 2);
                const std::string row = name + ": row " + std::to_string(id) + " of messages";
                auto it = topics.find(topic);
                if (it == topics.end())
                    throw Error(row + ": topic_id " + std::to_string(topic) + ", which the topics table does not list");
                if (t < 0) throw Error(row + ": negative timestamp " + std::to_string(t));
                MessageRef m;
                m.connection = it->second;
                m.logTimeNs = uint64_t(t);
                m.location[0] = f;
                m.location[1] = uint64_t(id);
                ++connections_[m.connection].messageCount;
                messages_.push_back(m);
            }
            if (sqlite3_prepare_v2(file.db, "SELECT data FROM messages WHERE id = ?", -1, &file.read, nullptr) != SQLITE_OK)
                fail(file, "cannot prepare the message query");
        }
        std::stable_sort(messages_.begin(), messages_.end(),
                         [](const MessageRef& a, const MessageRef& b) { return a.logTimeNs < b.logTimeNs; });
    }

    std::string formatName() const override { return "rosbag2 SQLite"; }

    std::vector<uint8_t> read(const MessageRef& m) const override {
        const std::string where = path_.string() + ": " + describe(m);
        if (m.location[0] >= files_.size()) throw Error(where + ": no such file in the recording");
        File& file = *files_[m.location[0]];
        // One prepared statement per file, used under its lock (SQLite connections are opened NOMUTEX).
        std::lock_guard lock(file.mutex);
        sqlite3_reset(file.read);
        sqlite3_bind_int64(file.read, 1, static_cast<sqlite3_int64>(m.location[1]));
        int rc = sqlite3_step(file.read);
        if (rc == SQLITE_DONE) throw Error(where + ": no such row in " + file.path.string());
        if (rc != SQLITE_ROW) throw Error(where + ": " + sqlite3_errmsg(file.db));
        const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(file.read, 0));
        int n = sqlite3_column_bytes(file.read, 0);
        std::vector<uint8_t> out(p, p + (p ? n : 0));
        sqlite3_reset(file.read);
        return out;
    }

protected:
    std::string describeLocation(const MessageRef& m) const override {
        std::string file = m.location[0] < files_.size() ? files_[m.location[0]]->path.filename().string()
                                                         : "file " + std::to_string(m.location[0]);
        return "row " + std::to_string(m.location[1]) + " of " + file;
    }

private:
    struct File {
        fs::path path;
        sqlite3* db = nullptr;
        sqlite3_stmt* read = nullptr;
        std::mutex mutex;
        // Here rather than in ~Rosbag2Sqlite: a constructor that throws half-way closes what it opened too.
        ~File() {
            sqlite3_finalize(read);
            sqlite3_close(db);
        }
    };
    struct Statement {
        Statement(File& f, const char* sql) : file(f) {
            if (sqlite3_prepare_v2(f.db, sql, -1, &s, nullptr) != SQLITE_OK)
                fail(f, "not a rosbag2 database (" + std::string(sql) + ")");
        }
        ~Statement() { sqlite3_finalize(s); }
        bool step() {
            int rc = sqlite3_step(s);
            if (rc == SQLITE_ROW) return true;
            if (rc == SQLITE_DONE) return false;
            throw Error(file.path.string() + ": " + sqlite3_errmsg(file.db));
        }
        File& file;
        sqlite3_stmt* s = nullptr;
    };

    static std::string text(sqlite3_stmt* s, int col) {
        const unsigned char* t = sqlite3_column_text(s, col);
        return t ? std::string(reinterpret_cast<const char*>(t)) : std::string();
    }
    [[noreturn]] static void fail(const File& f, const std::string& what) {
        throw Error(f.path.string() + ": " + what + ": " + (f.db ? sqlite3_errmsg(f.db) : "out of memory"));
    }

    // unique_ptr: File holds a mutex, which does not move.
    std::vector<std::unique_ptr<File>> files_;
};

}  // namespace

namespace detail {

Rosbag2Folder readRosbag2Folder(const fs::path& dir) {
    Rosbag2Folder out;
    std::ifstream in(dir / "metadata.yaml");
    if (!in) throw Error((dir / "metadata.yaml").string() + ": cannot read");
    std::vector<std::string> listed;
    bool inList = false;
    for (std::string line; std::getline(in, line);) {
        std::string t = trim(line);
        if (inList) {
            if (t.starts_with("- ")) {
                listed.push_back(trim(t.substr(2)));
                continue;
            }
            inList = false;
        }
        if (t.starts_with("storage_identifier:")) out.storage = trim(t.substr(19));
        else if (t == "relative_file_paths:") inList = true;
    }
    std::error_code ec;  // the error_code overloads throughout: a filesystem_error is not a vkmesh::Error
    for (const std::string& rel : listed) {
        fs::path p = dir / rel;
        // Early rosbag2 releases listed the files with the bag folder's name in front.
        if (!fs::exists(p, ec) && fs::exists(dir / fs::path(rel).filename(), ec)) p = dir / fs::path(rel).filename();
        if (!fs::exists(p, ec))
            throw Error((dir / "metadata.yaml").string() + ": lists " + rel + ", which is not in the folder");
        out.files.push_back(p);
    }
    if (out.files.empty()) {
        std::vector<std::string> db3, mcap;
        for (const auto& e : fs::directory_iterator(dir, ec)) {
            if (e.path().extension() == ".db3") db3.push_back(e.path().filename().string());
            if (e.path().extension() == ".mcap") mcap.push_back(e.path().filename().string());
        }
        bool useMcap = out.storage == "mcap" || (out.storage.empty() && db3.empty());
        auto& names = useMcap ? mcap : db3;
        std::sort(names.begin(), names.end(), naturalLess);
        for (const auto& n : names) out.files.push_back(dir / n);
    }
    if (out.storage.empty())
        out.storage = !out.files.empty() && out.files.front().extension() == ".mcap" ? "mcap" : "sqlite3";
    if (out.storage != "sqlite3" && out.storage != "mcap")
        throw Error((dir / "metadata.yaml").string() + ": storage_identifier '" + out.storage +
                    "' (vkmesh reads sqlite3 and mcap)");
    if (out.files.empty())
        throw Error(dir.string() + ": a rosbag2 folder without any ." + (out.storage == "mcap" ? "mcap" : "db3") + " file");
    return out;
}

std::unique_ptr<Container> openRosbag2Sqlite(const fs::path& path, const std::vector<fs::path>& files) {
    return std::make_unique<Rosbag2Sqlite>(path, files);
}

}  // namespace detail

}  // namespace vkmesh::io::recording
