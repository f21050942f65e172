// MCAP (https://mcap.dev/spec): magic "\x89MCAP0\r\n", then records of <uint8 opcode><uint64 length><content>
// up to a Footer and the magic again. Schemas (0x03), channels (0x04) and messages (0x05) are read, at top
// level or inside chunks (0x06; compression "", "zstd" or "lz4" frames, CRC-32 checked when non-zero); every
// other record (indexes, attachments, metadata, statistics, and opcodes newer than this reader) is skipped
// by its length, as the spec asks.
//
// Indexed by a linear scan, not through the summary section: a recording cut off has none, and the scan then
// keeps the messages of its complete records, with a warning.
#include "io/recordings/byte_reader.h"
#include "io/recordings/decompress.h"
#include "io/recordings/file_source.h"
#include "io/recordings/openers.h"

#include "core/fuzzing.h"
#include "core/map_format.h"

#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <unordered_map>

namespace vkmesh::io::recording {

namespace {

using detail::ByteReader;
using detail::ByteSource;

const std::string kMagic("\x89MCAP0\r\n", 8);

enum Op : uint8_t { kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06,
                    kDataEnd = 0x0F };

// Message record content before its data: channel_id u16, sequence u32, log_time u64, publish_time u64.
constexpr uint64_t kMessagePrefix = 2 + 4 + 8 + 8;

std::string str(ByteReader& r, const char* what) { return std::string(r.take(r.u32(what), what)); }

struct Span {
    bool chunk = false;
    std::string compression;
    uint64_t size = 0;  // uncompressed
    uint32_t crc = 0;
    uint64_t dataOffset = 0, dataLength = 0;
};

class Mcap final : public Container {
public:
    Mcap(ByteSource source, const std::filesystem::path& path) : source_(std::move(source)) {
        path_ = path;
        name_ = path.string();
        index();
    }

    std::string formatName() const override { return "MCAP"; }

    std::vector<uint8_t> read(const MessageRef& m) const override {
        const std::string where = name_ + ": " + describe(m);
        auto it = spans_.find(m.location[0]);
        if (it == spans_.end()) throw Error(where + ": no chunk or message record starts at that byte");
        const Span& span = it->second;
        if (!span.chunk) {
            if (m.location[1] != 0) throw Error(where + ": an unchunked message has no offset");
            std::string content = source_.read(span.dataOffset, span.dataLength, where);
            return messageData(content, where);
        }
        std::shared_ptr<const std::vector<uint8_t>> chunk = chunkBytes(m.location[0], span, where);
        if (m.location[1] >= chunk->size())
            throw Error(where + ": the message lies past the end of its chunk (" + std::to_string(chunk->size()) + " bytes)");
        ByteReader r(std::string_view(reinterpret_cast<const char*>(chunk->data()), chunk->size()), where);
        r.take(m.location[1], "the chunk's records before the message");
        if (r.u8("opcode") != kMessage) throw Error(where + ": not a message record");
        return messageData(r.take(r.u64("record length"), "the message record"), where);
    }

protected:
    std::string describeLocation(const MessageRef& m) const override {
        auto it = spans_.find(m.location[0]);
        if (it != spans_.end() && !it->second.chunk) return "record at byte " + std::to_string(m.location[0]);
        return "chunk at byte " + std::to_string(m.location[0]) + ", message record at " +
               std::to_string(m.location[1]) + " inside it";
    }

private:
    struct Schema {
        std::string name, encoding;
    };
    struct Channel {
        uint16_t schema = 0;
        std::string topic, encoding;
    };
    struct Pending {
        uint16_t channel;
        MessageRef ref;
    };

    std::string at(uint64_t offset) const { return name_ + ": record at byte " + std::to_string(offset); }

    static std::vector<uint8_t> messageData(std::string_view content, const std::string& where) {
        if (content.size() < kMessagePrefix)
            throw Error(where + ": a message record of " + std::to_string(content.size()) + " bytes (at least " +
                        std::to_string(kMessagePrefix) + ")");
        content.remove_prefix(kMessagePrefix);
        return std::vector<uint8_t>(content.begin(), content.end());
    }

    std::vector<uint8_t> decompressChunk(const Span& span, const std::string& compressed, const std::string& where) const {
        std::vector<uint8_t> bytes = detail::decompress(span.compression, compressed, span.size, where + " (chunk)");
        // The fuzz targets skip the CRC, as the .vkmap reader skips its checksums: a fuzzer cannot fix a CRC-32 up
        // by mutation, and the records behind it are what is worth fuzzing (core/fuzzing.h).
        if (span.crc != 0 && !fuzzing::active()) {
            uint32_t crc = map::crc32(bytes.data(), bytes.size());
            if (crc != span.crc)
                throw Error(where + " (chunk): CRC-32 of the decompressed records is " + std::to_string(crc) +
                            ", the chunk declares " + std::to_string(span.crc));
        }
        return bytes;
    }

    std::shared_ptr<const std::vector<uint8_t>> chunkBytes(uint64_t offset, const Span& span,
                                                           const std::string& where) const {
        {
            std::lock_guard lock(cacheMutex_);
            if (cached_ && cachedOffset_ == offset) return cached_;
        }
        // Decompressed outside the lock: other threads' reads of other chunks need not wait for this one.
        std::string compressed = source_.read(span.dataOffset, span.dataLength, where);
        auto bytes = std::make_shared<const std::vector<uint8_t>>(decompressChunk(span, compressed, where));
        std::lock_guard lock(cacheMutex_);
        cached_ = bytes;
        cachedOffset_ = offset;
        return bytes;
    }

    void schema(std::string_view content, const std::string& where) {
        ByteReader r(content, where);
        uint16_t id = r.u16("schema id");
        Schema s;
        s.name = str(r, "schema name");
        s.encoding = str(r, "schema encoding");
        r.take(r.u32("schema data length"), "schema data");
        if (id == 0) throw Error(where + ": schema id 0 (reserved for 'no schema')");
        auto [it, added] = schemas_.emplace(id, s);
        if (!added && (it->second.name != s.name || it->second.encoding != s.encoding))
            throw Error(where + ": schema " + std::to_string(id) + " redefined as " + s.name + ", was " + it->second.name);
    }

    void channel(std::string_view content, const std::string& where) {
        ByteReader r(content, where);
        uint16_t id = r.u16("channel id");
        Channel c;
        c.schema = r.u16("schema id");
        c.topic = str(r, "topic");
        c.encoding = str(r, "message encoding");
        r.take(r.u32("metadata length"), "metadata");  // map<string, string>: not needed
        auto [it, added] = channels_.emplace(id, c);
        if (!added && (it->second.topic != c.topic || it->second.encoding != c.encoding || it->second.schema != c.schema))
            throw Error(where + ": channel " + std::to_string(id) + " redefined as " + c.topic + ", was " + it->second.topic);
    }

    void message(std::string_view content, uint64_t offset, uint64_t inner, const std::string& where) {
        ByteReader r(content, where);
        Pending p;
        r.need(kMessagePrefix, "the message record");
        p.channel = r.u16("channel id");
        r.u32("sequence");
        p.ref.logTimeNs = r.u64("log time");
        p.ref.location[0] = offset;
        p.ref.location[1] = inner;
        p.ref.keepHead(content.substr(kMessagePrefix));
        pending_.push_back(p);
    }

    void scanChunk(uint64_t offset, const std::vector<uint8_t>& chunk) {
        const std::string where = at(offset) + " (chunk)";
        ByteReader r(std::string_view(reinterpret_cast<const char*>(chunk.data()), chunk.size()), where);
        while (!r.atEnd()) {
            uint64_t inner = r.pos();
            const std::string innerWhere = where + ", record at " + std::to_string(inner) + " inside it";
            ByteReader rr(std::string_view(reinterpret_cast<const char*>(chunk.data()) + inner, r.remaining()), innerWhere);
            uint8_t op = rr.u8("opcode");
            std::string_view content = rr.take(rr.u64("record length"), "the record");
            r.take(rr.pos(), "the record");
            if (op == kSchema) schema(content, innerWhere);
            else if (op == kChannel) channel(content, innerWhere);
            else if (op == kMessage) message(content, offset, inner, innerWhere);
            // anything else inside a chunk: skipped, as unknown records are
        }
    }

    void index() {
        const uint64_t size = source_.size();
        if (size < kMagic.size() || source_.read(0, kMagic.size(), name_) != kMagic)
            throw Error(name_ + ": not an MCAP file (no MCAP magic at its start)");
        uint64_t pos = kMagic.size();
        bool footer = false;
        size_t records = 0;
        while (pos < size) {
            const uint64_t start = pos;
            const std::string where = at(start);
            if (size - pos < 9) {
                truncated(where, "the record's opcode and length", records);
                break;
            }
            std::string head = source_.read(pos, 9, where);
            ByteReader hr(head, where);
            uint8_t op = hr.u8("opcode");
            uint64_t len = hr.u64("record length");
            pos += 9;
            if (len > size - pos) {
                truncated(where, "a record of " + std::to_string(len) + " bytes", records);
                break;
            }
            const uint64_t contentOffset = pos;
            pos += len;
            ++records;
            if (op == kFooter) {
                footer = true;
                break;
            }
            if (op == kSchema || op == kChannel) {
                std::string content = source_.read(contentOffset, len, where);
                if (op == kSchema) schema(content, where);
                else channel(content, where);
            } else if (op == kMessage) {
                // Only the fields before the data: an unchunked image need not be read to be indexed.
                std::string prefix = source_.read(contentOffset, std::min<uint64_t>(len, kMessagePrefix), where);
                Span s;
                s.dataOffset = contentOffset;
                s.dataLength = len;
                spans_.emplace(start, std::move(s));
                message(prefix, start, 0, where);
            } else if (op == kChunk) {
                // The chunk's fields before its records, read on their own: the records may be megabytes.
                uint64_t fixed = std::min<uint64_t>(len, 8 + 8 + 8 + 4 + 4);
                std::string head2 = source_.read(contentOffset, fixed, where);
                ByteReader r(head2, where);
                r.u64("message start time");
                r.u64("message end time");
                Span s;
                s.chunk = true;
                s.size = r.u64("uncompressed size");
                s.crc = r.u32("uncompressed crc");
                uint32_t compLen = r.u32("compression");
                if (compLen > len - fixed) throw Error(where + ": truncated: the chunk's compression name");
                s.compression = source_.read(contentOffset + fixed, compLen, where);
                uint64_t used = fixed + compLen;
                if (len - used < 8) throw Error(where + ": truncated: the chunk's records length");
                std::string rl = source_.read(contentOffset + used, 8, where);
                uint64_t recordsLen = ByteReader(rl, where).u64("records length");
                used += 8;
                if (recordsLen > len - used)
                    throw Error(where + ": the chunk's records (" + std::to_string(recordsLen) +
                                " bytes) run past the end of the chunk record (" + std::to_string(len - used) + " left)");
                s.dataOffset = contentOffset + used;
                s.dataLength = recordsLen;
                std::string compressed = source_.read(s.dataOffset, s.dataLength, where);
                std::vector<uint8_t> chunk = decompressChunk(s, compressed, where);
                spans_.emplace(start, std::move(s));
                scanChunk(start, chunk);
            }
            // Header, DataEnd and every other opcode: skipped by its length (the summary section after DataEnd repeats
            // schemas and channels, which are read again harmlessly).
        }
        if (!footer && warnings_.empty())
            warnings_.push_back(name_ + ": no footer: the recording was not closed (cut off at byte " +
                                std::to_string(size) + "); its " + std::to_string(pending_.size()) +
                                " complete messages are read");
        resolve();
    }

    void truncated(const std::string& where, const std::string& what, size_t records) {
        std::string msg = where + ": " + what + " runs past the end of the file (" + std::to_string(source_.size()) +
                          " bytes): the MCAP file is truncated";
        if (records == 0 || pending_.empty()) throw Error(msg + ", before any complete message");
        warnings_.push_back(msg + "; its first " + std::to_string(pending_.size()) + " messages are read, the rest is lost");
    }

    void resolve() {
        std::map<std::tuple<std::string, std::string, std::string>, uint32_t> merged;
        std::unordered_map<uint16_t, uint32_t> toIndex;
        for (const auto& [id, c] : channels_) {
            std::string type;
            if (c.schema != 0) {
                auto s = schemas_.find(c.schema);
                if (s == schemas_.end())
                    throw Error(name_ + ": channel " + std::to_string(id) + " (" + c.topic + ") names schema " +
                                std::to_string(c.schema) + ", which the file does not define");
                type = detail::normaliseRosType(s->second.name);
            }
            auto [it, added] = merged.emplace(std::make_tuple(c.topic, type, c.encoding), uint32_t(connections_.size()));
            if (added) {
                Connection conn;
                conn.id = uint32_t(connections_.size());
                conn.topic = c.topic;
                conn.type = type;
                conn.encoding = c.encoding;
                // Only "ros1" and "cdr" decode; another encoding keeps Cdr here and is refused by its `encoding`.
                conn.serialization = c.encoding == "ros1" ? Serialization::Ros1 : Serialization::Cdr;
                connections_.push_back(std::move(conn));
            }
            toIndex[id] = it->second;
        }
        messages_.reserve(pending_.size());
        for (Pending& p : pending_) {
            auto it = toIndex.find(p.channel);
            if (it == toIndex.end())
                throw Error(at(p.ref.location[0]) + ", message record at " + std::to_string(p.ref.location[1]) +
                            ": a message on channel " + std::to_string(p.channel) + ", which the file does not define");
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
    std::map<uint16_t, Schema> schemas_;
    std::map<uint16_t, Channel> channels_;
    std::vector<Pending> pending_;
    mutable std::mutex cacheMutex_;
    mutable uint64_t cachedOffset_ = 0;
    mutable std::shared_ptr<const std::vector<uint8_t>> cached_;
};

}  // namespace

namespace detail {
std::unique_ptr<Container> openMcapFile(const std::filesystem::path& path) {
    return std::make_unique<Mcap>(ByteSource::openFile(path), path);
}
}  // namespace detail

std::unique_ptr<Container> openMcap(std::string_view bytes, const std::string& name) {
    return std::make_unique<Mcap>(detail::ByteSource::fromBytes(bytes), name);
}

}  // namespace vkmesh::io::recording
