// The message decoders of messages.h. One reader serves both serialisations: ROS 1 (little-endian, packed,
// strings as uint32 length + bytes) and CDR (XCDR1 as ROS 2's rmw layers write it: the 4-byte encapsulation
// header picks the byte order, each primitive is aligned to its size counted from the end of that header,
// strings carry a NUL counted in their length).
#include "io/recordings/messages.h"

#include <algorithm>
#include <bit>
#include <cstring>

namespace vkmesh::io::recording {

namespace {

class Decoder {
public:
    Decoder(std::span<const uint8_t> bytes, Serialization s, const std::string& where, const char* type)
        : bytes_(bytes), cdr_(s == Serialization::Cdr), where_(where), type_(type) {
        if (cdr_) {
            // Encapsulation identifier (big-endian uint16) and 2 option bytes.
            if (bytes.size() < 4) fail("shorter than the 4-byte CDR encapsulation header");
            if (bytes[0] != 0 || bytes[1] > 1) {
                const char* known = bytes[0] != 0 ? nullptr
                                    : bytes[1] == 2 || bytes[1] == 3 ? "PL_CDR (parameter list)"
                                    : bytes[1] >= 6 && bytes[1] <= 11 ? "XCDR2"
                                    : nullptr;
                fail(std::string("CDR encapsulation ") + hex(bytes[0]) + " " + hex(bytes[1]) +
                     (known ? std::string(" (") + known + ")" : std::string()) +
                     ": vkmesh reads plain CDR (00 00 big-endian, 00 01 little-endian)");
            }
            bigEndian_ = bytes[1] == 0;
            pos_ = 4;
            origin_ = 4;
        }
    }

    [[noreturn]] void fail(const std::string& what) const {
        throw Error(where_ + ": " + type_ + ": " + what);
    }

    void align(size_t n) {
        if (!cdr_) return;
        size_t misalign = (pos_ - origin_) % n;
        if (misalign) skip(n - misalign, "alignment padding");
    }
    void skip(size_t n, const char* what) {
        need(n, what);
        pos_ += n;
    }
    void need(uint64_t n, const char* what) const {
        if (n > bytes_.size() - pos_)
            fail(std::string("truncated: ") + what + " needs " + std::to_string(n) + " bytes at byte " +
                 std::to_string(pos_) + ", " + std::to_string(bytes_.size() - pos_) + " left");
    }

    template <typename T>
    T prim(const char* what) {
        align(sizeof(T));
        need(sizeof(T), what);
        uint8_t b[sizeof(T)];
        std::memcpy(b, bytes_.data() + pos_, sizeof(T));
        pos_ += sizeof(T);
        if (bigEndian_) std::reverse(b, b + sizeof(T));  // the host is little-endian (checked below)
        T v;
        std::memcpy(&v, b, sizeof(T));
        return v;
    }
    uint8_t u8(const char* w) { return prim<uint8_t>(w); }
    uint32_t u32(const char* w) { return prim<uint32_t>(w); }
    int32_t i32(const char* w) { return prim<int32_t>(w); }
    double f64(const char* w) { return prim<double>(w); }
    float f32(const char* w) { return prim<float>(w); }

    std::string string(const char* what) {
        uint32_t len = u32(what);
        need(len, what);
        const char* p = reinterpret_cast<const char*>(bytes_.data() + pos_);
        pos_ += len;
        if (!cdr_) return std::string(p, len);
        // CDR counts the terminating NUL; an empty string is 1 byte ("\0"), though some writers send length 0.
        if (len == 0) return {};
        if (p[len - 1] != '\0') fail(std::string(what) + ": a CDR string without its terminating NUL");
        return std::string(p, len - 1);
    }
    // A sequence's count, checked against the bytes left (each element takes at least `minElementBytes`)
    // before anything is allocated for it.
    uint32_t count(const char* what, size_t minElementBytes) {
        uint32_t n = u32(what);
        if (uint64_t(n) * minElementBytes > bytes_.size() - pos_)
            fail(std::string(what) + ": " + std::to_string(n) + " elements cannot fit in the " +
                 std::to_string(bytes_.size() - pos_) + " bytes left");
        return n;
    }

    MessageHeader header() {
        MessageHeader h;
        uint64_t sec = 0, nsec = 0;
        if (cdr_) {
            int32_t s = i32("header.stamp.sec");
            if (s < 0) fail("header.stamp.sec is negative (" + std::to_string(s) + ")");
            sec = uint64_t(s);
            nsec = u32("header.stamp.nanosec");
        } else {
            u32("header.seq");
            sec = u32("header.stamp.sec");
            nsec = u32("header.stamp.nsec");
        }
        if (nsec >= 1000000000u) fail("header.stamp has " + std::to_string(nsec) + " nanoseconds");
        h.stampNs = sec * 1000000000u + nsec;
        h.frameId = string("header.frame_id");
        return h;
    }

    TransformMessage transform() {
        TransformMessage t;
        for (int i = 0; i < 3; ++i) t.translation[i] = f64("transform.translation");
        double q[4];
        for (double& v : q) v = f64("transform.rotation");
        t.rotation = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);  // Eigen's constructor takes w first
        return t;
    }

    // ROS 1 messages end exactly with their last field; CDR writers may pad the end to the alignment of the
    // largest primitive (8 bytes at most), nothing more.
    void end() {
        size_t left = bytes_.size() - pos_;
        if (!cdr_ && left != 0) fail(std::to_string(left) + " bytes of trailing garbage after the message");
        if (cdr_ && left >= 8) fail(std::to_string(left) + " bytes of trailing garbage after the message");
    }

    std::span<const uint8_t> bytes(size_t n, const char* what) {
        need(n, what);
        auto s = bytes_.subspan(pos_, n);
        pos_ += n;
        return s;
    }

private:
    static std::string hex(uint8_t v) {
        const char* d = "0123456789abcdef";
        return {d[v >> 4], d[v & 15]};
    }
    std::span<const uint8_t> bytes_;
    bool cdr_;
    bool bigEndian_ = false;
    size_t pos_ = 0, origin_ = 0;
    const std::string& where_;
    const char* type_;
};

static_assert(std::endian::native == std::endian::little, "the decoders assume a little-endian host");

}  // namespace

std::optional<MessageHeader> decodeLeadingHeader(std::span<const uint8_t> head, Serialization s) {
    // The same reader on the first bytes: a header that does not fit in them (a long frame id) throws, and the
    // caller reads the whole message instead.
    const std::string where = "a message's leading bytes";  // the Decoder keeps a reference to it
    try {
        Decoder d(head, s, where, "std_msgs/Header");
        return d.header();
    } catch (const Error&) {
        return std::nullopt;
    }
}

ImageMessage decodeImage(std::span<const uint8_t> bytes, Serialization s, const std::string& where) {
    Decoder d(bytes, s, where, "sensor_msgs/Image");
    ImageMessage m;
    m.header = d.header();
    m.height = d.u32("height");
    m.width = d.u32("width");
    m.encoding = d.string("encoding");
    m.bigEndian = d.u8("is_bigendian") != 0;
    m.step = d.u32("step");
    uint32_t n = d.count("data", 1);
    auto data = d.bytes(n, "data");
    d.end();
    if (uint64_t(m.step) * m.height > n)
        d.fail("step " + std::to_string(m.step) + " x height " + std::to_string(m.height) + " = " +
               std::to_string(uint64_t(m.step) * m.height) + " bytes, but the image holds " + std::to_string(n));
    m.data.assign(data.begin(), data.end());
    return m;
}

CameraInfoMessage decodeCameraInfo(std::span<const uint8_t> bytes, Serialization s, const std::string& where) {
    Decoder d(bytes, s, where, "sensor_msgs/CameraInfo");
    CameraInfoMessage m;
    m.header = d.header();
    m.height = d.u32("height");
    m.width = d.u32("width");
    m.distortionModel = d.string("distortion_model");
    uint32_t n = d.count("D", 8);
    m.d.resize(n);
    for (double& v : m.d) v = d.f64("D");
    for (double& v : m.k) v = d.f64("K");
    for (double& v : m.r) v = d.f64("R");
    for (double& v : m.p) v = d.f64("P");
    d.u32("binning_x");
    d.u32("binning_y");
    d.u32("roi.x_offset");
    d.u32("roi.y_offset");
    d.u32("roi.height");
    d.u32("roi.width");
    d.u8("roi.do_rectify");
    d.end();
    return m;
}

std::vector<TransformStampedMessage> decodeTfMessage(std::span<const uint8_t> bytes, Serialization s,
                                                     const std::string& where) {
    Decoder d(bytes, s, where, "tf2_msgs/TFMessage");
    // The smallest TransformStamped: a header (12 bytes ROS 1, 8 CDR) and an empty frame id (4), an empty
    // child frame id (4), 7 float64 (56).
    uint32_t n = d.count("transforms", 8 + 4 + 4 + 56);
    std::vector<TransformStampedMessage> out(n);
    for (auto& t : out) {
        t.header = d.header();
        t.childFrameId = d.string("child_frame_id");
        t.transform = d.transform();
    }
    d.end();
    return out;
}

TransformMessage decodeTransform(std::span<const uint8_t> bytes, Serialization s, const std::string& where) {
    Decoder d(bytes, s, where, "geometry_msgs/Transform");
    TransformMessage t = d.transform();
    d.end();
    return t;
}

float decodeFloat32(std::span<const uint8_t> bytes, Serialization s, const std::string& where) {
    Decoder d(bytes, s, where, "std_msgs/Float32");
    float v = d.f32("data");
    d.end();
    return v;
}

uint32_t decodeUInt32(std::span<const uint8_t> bytes, Serialization s, const std::string& where) {
    Decoder d(bytes, s, where, "std_msgs/UInt32");
    uint32_t v = d.u32("data");
    d.end();
    return v;
}

std::string decodeString(std::span<const uint8_t> bytes, Serialization s, const std::string& where) {
    Decoder d(bytes, s, where, "std_msgs/String");
    std::string v = d.string("data");
    d.end();
    return v;
}

KeyValueMessage decodeKeyValue(std::span<const uint8_t> bytes, Serialization s, const std::string& where) {
    Decoder d(bytes, s, where, "diagnostic_msgs/KeyValue");
    KeyValueMessage m;
    m.key = d.string("key");
    m.value = d.string("value");
    d.end();
    return m;
}

}  // namespace vkmesh::io::recording
