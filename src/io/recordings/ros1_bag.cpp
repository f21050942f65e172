// ROS 1 bag format 2.0 (http://wiki.ros.org/Bags/Format/2.0): "#ROSBAG V2.0\n", then records of
// <uint32 header_len><header: fields uint32 len + "name=value"><uint32 data_len><data>. Messages (op 0x02) and
// connections (op 0x07) sit inside chunks (op 0x05, compression none/bz2/lz4); index data (0x04), chunk info
// (0x06) and the bag header's index_pos only speed up ROS's own reader.
//
// Indexed by a linear scan of the whole file that decompresses every chunk, rather than through the index
// section: a recording cut off (the recorder killed, the disk full) has no index section, and the scan reads
// such a bag up to its last complete chunk, with a warning. The price is one read of the file at open.
#include "io/recordings/byte_reader.h"
#include "io/recordings/decompress.h"
#include "io/recordings/file_source.h"
#include "io/recordings/openers.h"

#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>

namespace vkmesh::io::recording {

namespace {

using detail::ByteReader;
using detail::ByteSource;

const std::string kMagic = "#ROSBAG V2.0\n";

enum Op : uint8_t { kMessageData = 0x02, kBagHeader = 0x03, kIndexData = 0x04, kChunk = 0x05, kChunkInfo = 0x06,
                    kConnection = 0x07 };

// A record header's fields, "name=value" with binary values.
class Fields {
public:
    Fields(std::string_view header, const std::string& where) : where_(where) {
        ByteReader r(header, where);
        while (!r.atEnd()) {
            uint32_t len = r.u32("a header field's length");
            std::string_view f = r.take(len, "a header field");
            size_t eq = f.find('=');
            if (eq == std::string_view::npos || eq == 0)
                throw Error(where + ": a header field without 'name=' (" + std::to_string(len) + " bytes)");
            fields_.emplace_back(f.substr(0, eq), f.substr(eq + 1));
        }
    }
    std::optional<std::string_view> find(std::string_view name) const {
        for (const auto& [n, v] : fields_)
            if (n == name) return v;
        return std::nullopt;
    }
    std::string_view get(std::string_view name) const {
        auto v = find(name);
        if (!v) throw Error(where_ + ": the header has no '" + std::string(name) + "' field");
        return *v;
    }
    template <typename T>
    T integer(std::string_view name) const {
        std::string_view v = get(name);
        if (v.size() != sizeof(T))
            throw Error(where_ + ": header field '" + std::string(name) + "' has " + std::to_string(v.size()) +
                        " bytes, not " + std::to_string(sizeof(T)));
        return ByteReader(v, where_).le<T>("a header field");
    }
    // ROS time: uint32 sec, uint32 nsec.
    uint64_t timeNs(std::string_view name) const {
        std::string_view v = get(name);
        if (v.size() != 8) throw Error(where_ + ": header field 'time' has " + std::to_string(v.size()) + " bytes, not 8");
        ByteReader r(v, where_);
        uint64_t sec = r.u32("time"), nsec = r.u32("time");
        if (nsec >= 1000000000u) throw Error(where_ + ": time with " + std::to_string(nsec) + " nanoseconds");
        return sec * 1000000000u + nsec;
    }

private:
    const std::string& where_;
    std::vector<std::pair<std::string_view, std::string_view>> fields_;
};

// One record parsed from a buffer (a decompressed chunk).
struct Record {
    std::string_view header, data;
};
Record nextRecord(ByteReader& r) {
    Record rec;
    rec.header = r.take(r.u32("the record's header length"), "the record's header");
    rec.data = r.take(r.u32("the record's data length"), "the record's data");
    return rec;
}

// Where the bytes of a chunk (or an unchunked message record) lie in the file.
struct Span {
    bool chunk = false;
    std::string compression;
    uint64_t size = 0;  // uncompressed
    uint64_t dataOffset = 0, dataLength = 0;
};

class Ros1Bag final : public Container {
public:
    Ros1Bag(ByteSource source, const std::filesystem::path& path) : source_(std::move(source)) {
        path_ = path;
        name_ = path.string();
        index();
    }

    std::string formatName() const override { return "ROS 1 bag"; }

    std::vector<uint8_t> read(const MessageRef& m) const override {
        auto it = spans_.find(m.location[0]);
        if (it == spans_.end())
            throw Error(name_ + ": " + describe(m) + ": no chunk or message record starts at that byte");
        const Span& span = it->second;
        if (!span.chunk) {
            if (m.location[1] != 0) throw Error(name_ + ": " + describe(m) + ": an unchunked message has no offset");
            std::string where = name_ + ": " + describe(m);
            std::string bytes = source_.read(span.dataOffset, span.dataLength, where);
            return std::vector<uint8_t>(bytes.begin(), bytes.end());
        }
        std::string where = name_ + ": " + describe(m);
        std::shared_ptr<const std::vector<uint8_t>> chunk = chunkBytes(m.location[0], span, where);
        if (m.location[1] >= chunk->size())
            throw Error(where + ": the message lies past the end of its chunk (" + std::to_string(chunk->size()) +
                        " bytes)");
        ByteReader r(std::string_view(reinterpret_cast<const char*>(chunk->data()), chunk->size()), where);
        r.take(m.location[1], "the chunk's records before the message");
        Record rec = nextRecord(r);
        Fields f(rec.header, where);
        if (f.integer<uint8_t>("op") != kMessageData) throw Error(where + ": not a message data record");
        return std::vector<uint8_t>(rec.data.begin(), rec.data.end());
    }

protected:
    std::string describeLocation(const MessageRef& m) const override {
        auto it = spans_.find(m.location[0]);
        if (it != spans_.end() && !it->second.chunk) return "record at byte " + std::to_string(m.location[0]);
        return "chunk at byte " + std::to_string(m.location[0]) + ", message record at " +
               std::to_string(m.location[1]) + " inside it";
    }

private:
    struct RosConnection {
        std::string topic, type;
    };
    struct Pending {
        uint32_t rosConnection;
        MessageRef ref;
    };

    std::string at(uint64_t offset) const { return name_ + ": record at byte " + std::to_string(offset); }

    std::shared_ptr<const std::vector<uint8_t>> chunkBytes(uint64_t offset, const Span& span,
                                                           const std::string& where) const {
        {
            std::lock_guard lock(cacheMutex_);
            if (cached_ && cachedOffset_ == offset) return cached_;
        }
        // Decompressed outside the lock: other threads' reads of other chunks need not wait for this one.
        std::string compressed = source_.read(span.dataOffset, span.dataLength, where);
        auto bytes = std::make_shared<const std::vector<uint8_t>>(
            detail::decompress(span.compression, compressed, span.size, where + ", chunk"));
        std::lock_guard lock(cacheMutex_);
        cached_ = bytes;
        cachedOffset_ = offset;
        return bytes;
    }

    // The connection record's fields: conn and topic in its header, type (and md5sum, message_definition, ...)
    // in its data, itself a header of fields.
    void connection(const Fields& f, std::string_view data, const std::string& where) {
        uint32_t id = f.integer<uint32_t>("conn");
        RosConnection c;
        c.topic = std::string(f.get("topic"));
        Fields d(data, where);
        c.type = std::string(d.get("type"));
        auto [it, added] = rosConnections_.emplace(id, c);
        if (!added && (it->second.topic != c.topic || it->second.type != c.type))
            throw Error(where + ": connection " + std::to_string(id) + " redefined as " + c.topic + " (" + c.type +
                        "), was " + it->second.topic + " (" + it->second.type + ")");
    }

    void message(const Fields& f, uint64_t offset, uint64_t inner, std::string_view data = {}) {
        Pending p;
        p.ref.keepHead(data);
        p.rosConnection = f.integer<uint32_t>("conn");
        p.ref.logTimeNs = f.timeNs("time");
        p.ref.location[0] = offset;
        p.ref.location[1] = inner;
        pending_.push_back(std::move(p));
    }

    void scanChunk(uint64_t offset, const std::vector<uint8_t>& chunk) {
        std::string where = at(offset) + " (chunk)";
        ByteReader r(std::string_view(reinterpret_cast<const char*>(chunk.data()), chunk.size()), where);
        while (!r.atEnd()) {
            uint64_t inner = r.pos();
            std::string innerWhere = where + ", record at " + std::to_string(inner) + " inside it";
            ByteReader rr(std::string_view(reinterpret_cast<const char*>(chunk.data()) + inner, r.remaining()),
                          innerWhere);
            Record rec = nextRecord(rr);
            r.take(rr.pos(), "the record");
            Fields f(rec.header, innerWhere);
            uint8_t op = f.integer<uint8_t>("op");
            if (op == kMessageData)
                message(f, offset, inner, rec.data);
            else if (op == kConnection)
                connection(f, rec.data, innerWhere);
            else
                throw Error(innerWhere + ": op 0x" + hex(op) + " inside a chunk (only messages and connections belong there)");
        }
    }

    static std::string hex(uint8_t v) {
        const char* d = "0123456789abcdef";
        return {d[v >> 4], d[v & 15]};
    }

    void index() {
        const uint64_t size = source_.size();
        if (size < kMagic.size() || source_.read(0, kMagic.size(), name_) != kMagic)
            throw Error(name_ + ": not a ROS 1 bag 2.0 (no \"#ROSBAG V2.0\" at its start)");
        uint64_t pos = kMagic.size();
        size_t chunks = 0;
        while (pos < size) {
            const uint64_t start = pos;
            const std::string where = at(start);
            // A record that runs past the end: the bag was cut off. Its complete chunks are kept.
            auto truncated = [&](const std::string& what) {
                std::string msg = where + ": " + what + " runs past the end of the file (" + std::to_string(size) +
                                  " bytes): the bag is truncated";
                if (chunks == 0) throw Error(msg + ", before any complete chunk");
                warnings_.push_back(msg + "; the " + std::to_string(pending_.size()) + " messages of its first " +
                                    std::to_string(chunks) + " chunks are read, the rest is lost");
            };
            auto u32At = [&](uint64_t p) {
                std::string b = source_.read(p, 4, where);
                return ByteReader(b, where).u32("a length");
            };
            if (size - pos < 4) { truncated("the header length"); break; }
            uint64_t headerLen = u32At(pos);
            pos += 4;
            if (headerLen > size - pos) { truncated("the header of " + std::to_string(headerLen) + " bytes"); break; }
            std::string header = source_.read(pos, headerLen, where);
            pos += headerLen;
            if (size - pos < 4) { truncated("the data length"); break; }
            uint64_t dataLen = u32At(pos);
            pos += 4;
            const uint64_t dataOffset = pos;
            if (dataLen > size - pos) { truncated("the data of " + std::to_string(dataLen) + " bytes"); break; }
            pos += dataLen;

            Fields f(header, where);
            uint8_t op = f.integer<uint8_t>("op");
            switch (op) {
            case kBagHeader:
                // rosbag's encrypted bags (AES or GPG plugins) name their encryptor here; their chunks are not
                // compressed data, and would otherwise fail as corrupt ones.
                if (auto e = f.find("encryptor"); e && !e->empty() && *e != "rosbag/NoEncryptor")
                    throw Error(where + ": an encrypted bag (" + std::string(*e) + "): vkmesh reads unencrypted bags");
                break;
            case kIndexData:
            case kChunkInfo: break;  // the index: not needed by the scan
            case kChunk: {
                Span s;
                s.chunk = true;
                s.compression = std::string(f.get("compression"));
                s.size = f.integer<uint32_t>("size");
                s.dataOffset = dataOffset;
                s.dataLength = dataLen;
                std::string compressed = source_.read(dataOffset, dataLen, where);
                std::vector<uint8_t> chunk = detail::decompress(s.compression, compressed, s.size, where + " (chunk)");
                spans_.emplace(start, std::move(s));
                scanChunk(start, chunk);
                ++chunks;
                break;
            }
            case kConnection: connection(f, source_.read(dataOffset, dataLen, where), where); break;
            case kMessageData: {
                // Not written by ROS's recorder (bag 2.0 always chunks), but the format allows it.
                Span s;
                s.dataOffset = dataOffset;
                s.dataLength = dataLen;
                spans_.emplace(start, std::move(s));
                message(f, start, 0);
                break;
            }
            default: throw Error(where + ": unknown op 0x" + hex(op));
            }
        }
        resolve();
    }

    // Messages to Connections: ROS connection ids are resolved once every connection record is known, and
    // connections on the same topic with the same type (several publishers) merged.
    void resolve() {
        std::map<std::pair<std::string, std::string>, uint32_t> byTopicType;
        std::unordered_map<uint32_t, uint32_t> toIndex;
        for (const auto& [id, c] : rosConnections_) {
            auto [it, added] = byTopicType.emplace(std::make_pair(c.topic, c.type), uint32_t(connections_.size()));
            if (added) {
                Connection conn;
                conn.id = uint32_t(connections_.size());
                conn.topic = c.topic;
                conn.type = c.type;
                conn.serialization = Serialization::Ros1;
                conn.encoding = "ros1";
                connections_.push_back(std::move(conn));
            }
            toIndex[id] = it->second;
        }
        messages_.reserve(pending_.size());
        for (Pending& p : pending_) {
            auto it = toIndex.find(p.rosConnection);
            if (it == toIndex.end())
                throw Error(at(p.ref.location[0]) + ", message record at " + std::to_string(p.ref.location[1]) +
                            ": a message on connection " + std::to_string(p.rosConnection) +
                            ", which the bag does not define");
            p.ref.connection = it->second;
            ++connections_[it->second].messageCount;
            messages_.push_back(p.ref);
        }
        pending_.clear();
        std::stable_sort(messages_.begin(), messages_.end(),
                         [](const MessageRef& a, const MessageRef& b) { return a.logTimeNs < b.logTimeNs; });
    }

    ByteSource source_;
    std::string name_;
    std::unordered_map<uint64_t, Span> spans_;
    std::map<uint32_t, RosConnection> rosConnections_;
    std::vector<Pending> pending_;
    // The last chunk decompressed by read(): a frame's colour and depth are usually in the same chunk.
    mutable std::mutex cacheMutex_;
    mutable uint64_t cachedOffset_ = 0;
    mutable std::shared_ptr<const std::vector<uint8_t>> cached_;
};

}  // namespace

namespace detail {
std::unique_ptr<Container> openRos1BagFile(const std::filesystem::path& path) {
    return std::make_unique<Ros1Bag>(ByteSource::openFile(path), path);
}
}  // namespace detail

std::unique_ptr<Container> openRos1Bag(std::string_view bytes, const std::string& name) {
    return std::make_unique<Ros1Bag>(detail::ByteSource::fromBytes(bytes), name);
}

}  // namespace vkmesh::io::recording
