// Recordings as datasets (recording_source.h; docs/RECORDINGS.md): topic choice, depth/colour pairing,
// calibration, depth unit, extrinsics and /tf poses, then per-frame decoding.
#include "io/datasets/recording_source.h"
#include "io/recordings/messages.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>

namespace vkmesh::datasets {

using namespace io::text;
using recording::CameraInfoMessage;
using recording::Connection;
using recording::Container;
using recording::ImageMessage;
using recording::MessageRef;

namespace {

// Depth and colour are paired by time with the rule TUM's rgb.txt association uses: the nearest within 20 ms.
constexpr uint64_t kPairingToleranceNs = 20'000'000;
// A /tf sample is used for a depth frame when it is this near in time (TUM's groundtruth.txt rule).
constexpr uint64_t kPoseToleranceNs = 20'000'000;

const std::set<std::string> kDepthEncodings = {"16UC1", "mono16", "32FC1"};
const std::set<std::string> kColorEncodings = {"rgb8", "bgr8", "rgba8", "bgra8", "mono8"};

bool isImageType(const std::string& t) { return t == "sensor_msgs/Image"; }
bool isCameraInfoType(const std::string& t) { return t == "sensor_msgs/CameraInfo"; }
bool isTfType(const std::string& t) { return t == "tf2_msgs/TFMessage" || t == "tf/tfMessage"; }

std::string lowerCase(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

bool nameSays(const std::string& topic, std::initializer_list<const char*> words) {
    const std::string t = lowerCase(topic);
    return std::any_of(words.begin(), words.end(), [&](const char* w) { return t.find(w) != std::string::npos; });
}

size_t commonPrefix(const std::string& a, const std::string& b) {
    size_t n = 0;
    while (n < a.size() && n < b.size() && a[n] == b[n]) ++n;
    return n;
}

// The header time of a message, falling back to the recording time where a publisher left the stamp at zero.
uint64_t stampOf(const recording::MessageHeader& h, const MessageRef& m) { return h.stampNs != 0 ? h.stampNs : m.logTimeNs; }

Pose poseOf(const recording::TransformMessage& t, const std::string& where) {
    Eigen::Quaterniond q = t.rotation;
    const double n = q.norm();
    if (!std::isfinite(n) || n < 0.5 || n > 2.0 || !t.translation.allFinite())
        throw Error(where + ": transform with rotation (" + fmt(q.x()) + " " + fmt(q.y()) + " " + fmt(q.z()) + " " +
                    fmt(q.w()) + ") and translation (" + fmt(t.translation.x()) + " " + fmt(t.translation.y()) + " " +
                    fmt(t.translation.z()) + ") is not a rigid transform");
    // The same conversion as a trajectory file's line (io/trajectory.cpp), so that a recording made from a
    // folder gives the folder's poses bit for bit.
    q.normalize();
    Pose T = Pose::Identity();
    T.topLeftCorner<3, 3>() = q.toRotationMatrix();
    T.topRightCorner<3, 1>() = t.translation;
    return T;
}

Pose inverseRigid(const Pose& T) {
    Pose inv = Pose::Identity();
    inv.topLeftCorner<3, 3>() = T.topLeftCorner<3, 3>().transpose();
    inv.topRightCorner<3, 1>() = -T.topLeftCorner<3, 3>().transpose() * T.topRightCorner<3, 1>();
    return inv;
}

// Frame names compared without a leading '/' (ROS 1's tf used "/openni_rgb_optical_frame", tf2 drops it).
std::string frameName(const std::string& f) { return !f.empty() && f[0] == '/' ? f.substr(1) : f; }

// The transforms in /tf and /tf_static: for each child frame, its parent and the samples over time.
class TfTree {
public:
    struct Sample {
        uint64_t stampNs;
        Pose parentFromChild;
    };
    struct Edge {
        std::string parent;
        bool isStatic = false;
        std::vector<Sample> samples;  // sorted by time once finish() ran
    };

    void add(const recording::TransformStampedMessage& t, bool isStatic, const std::string& where) {
        const std::string child = frameName(t.childFrameId), parent = frameName(t.header.frameId);
        if (child.empty() || parent.empty() || child == parent) return;
        Edge& e = edges_[child];
        if (e.samples.empty()) e.parent = parent;
        if (e.parent != parent) {
            // A frame whose parent changes over time is not a tree tf could use either; keep the first.
            conflicts_.insert(child);
            return;
        }
        e.isStatic = e.isStatic || isStatic;
        e.samples.push_back({t.header.stampNs, poseOf(t.transform, where)});
    }
    void finish() {
        for (auto& [child, e] : edges_)
            std::stable_sort(e.samples.begin(), e.samples.end(),
                             [](const Sample& a, const Sample& b) { return a.stampNs < b.stampNs; });
    }
    bool has(const std::string& frame) const { return edges_.count(frameName(frame)) > 0; }
    const std::set<std::string>& conflicts() const { return conflicts_; }

    // root_T_frame at time t, and the root's name; nothing when an edge on the way has no sample within the
    // tolerance. Static edges hold at every time.
    struct Lookup {
        Pose rootFromFrame;
        std::string root;
        bool anyDynamic = false;
    };
    std::optional<Lookup> lookup(const std::string& frameIn, uint64_t t) const {
        std::string frame = frameName(frameIn);
        std::optional<Pose> acc;  // starts at the first edge's transform, so one edge gives its pose exactly
        Lookup out;
        for (int depth = 0; depth < 64; ++depth) {
            auto it = edges_.find(frame);
            if (it == edges_.end()) break;
            const Edge& e = it->second;
            const Sample* best = nullptr;
            if (e.isStatic) {
                best = &e.samples.back();
            } else {
                auto after = std::lower_bound(e.samples.begin(), e.samples.end(), t,
                                              [](const Sample& s, uint64_t v) { return s.stampNs < v; });
                uint64_t bestGap = std::numeric_limits<uint64_t>::max();
                if (after != e.samples.end()) {
                    best = &*after;
                    bestGap = after->stampNs - t;
                }
                if (after != e.samples.begin() && t - std::prev(after)->stampNs < bestGap) {
                    best = &*std::prev(after);
                    bestGap = t - best->stampNs;
                }
                if (!best || bestGap > kPoseToleranceNs) return std::nullopt;
                out.anyDynamic = true;
            }
            acc = acc ? Pose(best->parentFromChild * *acc) : best->parentFromChild;
            frame = e.parent;
        }
        if (!acc) return std::nullopt;
        out.rootFromFrame = *acc;
        out.root = frame;
        return out;
    }

private:
    std::map<std::string, Edge> edges_;
    std::set<std::string> conflicts_;
};

// librealsense's layout: /device_<d>/sensor_<s>/<Stream>_<i>/image/data; the stream's prefix and its sensor's.
struct RealSenseStream {
    std::string stream;  // "/device_0/sensor_0/Depth_0"
    std::string sensor;  // "/device_0/sensor_0"
};
std::optional<RealSenseStream> realSenseStream(const std::string& topic) {
    const std::string suffix = "/image/data";
    if (topic.rfind("/device_", 0) != 0 || topic.size() <= suffix.size() ||
        topic.compare(topic.size() - suffix.size(), suffix.size(), suffix) != 0)
        return std::nullopt;
    const std::string stream = topic.substr(0, topic.size() - suffix.size());
    const size_t slash = stream.rfind('/');
    if (slash == 0 || slash == std::string::npos) return std::nullopt;
    const std::string sensor = stream.substr(0, slash);
    if (sensor.find("/sensor_") == std::string::npos) return std::nullopt;
    return RealSenseStream{stream, sensor};
}

struct ImageTopic {
    const Connection* connection;
    ImageMessage first;  // its first message, decoded (encoding, size, frame id)
};

std::string listTopics(const std::vector<ImageTopic>& topics) {
    std::string s;
    for (const auto& t : topics)
        s += (s.empty() ? "" : ", ") + t.connection->topic + " (" + t.first.encoding + ", " +
             std::to_string(t.first.width) + "x" + std::to_string(t.first.height) + ", " +
             std::to_string(t.connection->messageCount) + " messages)";
    return s;
}

// The topic the user named, or the one candidate, or the one whose name says what it is; else an Error that
// lists the candidates and names the option that chooses.
const ImageTopic* chooseTopic(const std::vector<ImageTopic>& all, const std::vector<ImageTopic>& candidates,
                              const std::string& chosen, const char* option, const char* what,
                              std::initializer_list<const char*> preferredWords, const std::string& file) {
    if (!chosen.empty()) {
        for (const auto& t : all)
            if (t.connection->topic == chosen) return &t;
        throw Error(file + ": " + option + " " + chosen + " is not a sensor_msgs/Image topic of this recording; its image topics: " +
                    (all.empty() ? std::string("none") : listTopics(all)));
    }
    if (candidates.empty()) return nullptr;
    if (candidates.size() == 1) return &candidates.front();
    std::vector<const ImageTopic*> named;
    for (const auto& t : candidates)
        if (nameSays(t.connection->topic, preferredWords)) named.push_back(&t);
    if (named.size() == 1) return named.front();
    throw Error(file + ": several " + what + " topics (" + listTopics(candidates) + "); choose one with " + option);
}

void copyRows(const ImageMessage& m, size_t bytesPerPixel, const std::string& where) {
    if (m.width == 0 || m.height == 0) throw Error(where + ": image is empty (" + std::to_string(m.width) + "x" + std::to_string(m.height) + ")");
    if (m.width > io::kMaxDepthImageSide || m.height > io::kMaxDepthImageSide ||
        uint64_t(m.width) * m.height > io::kMaxDepthImagePixels)
        throw Error(where + ": image of " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                    " pixels is larger than vkmesh accepts (" + std::to_string(io::kMaxDepthImageSide) + " per side)");
    if (uint64_t(m.step) < uint64_t(m.width) * bytesPerPixel || uint64_t(m.step) * m.height > m.data.size())
        throw Error(where + ": " + m.encoding + " image of " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                    " has a row step of " + std::to_string(m.step) + " bytes and " + std::to_string(m.data.size()) +
                    " bytes of data; it needs at least " + std::to_string(m.width * bytesPerPixel) + " per row");
}

DepthImage depthFromMessage(const ImageMessage& m, double depthScale, float maxDepth, const std::string& where) {
    DepthImage out;
    if (m.encoding == "16UC1" || m.encoding == "mono16") {
        copyRows(m, 2, where);
        std::vector<uint16_t> raw(size_t(m.width) * m.height);
        for (uint32_t y = 0; y < m.height; ++y) {
            const uint8_t* row = m.data.data() + size_t(y) * m.step;
            for (uint32_t x = 0; x < m.width; ++x) {
                const uint8_t a = row[2 * x], b = row[2 * x + 1];
                raw[size_t(y) * m.width + x] = m.bigEndian ? uint16_t(a << 8 | b) : uint16_t(b << 8 | a);
            }
        }
        // The one conversion a folder's PNGs get too, so the same samples give the same metres.
        io::rawDepthToMeters(raw.data(), int(m.width), int(m.height), m.width, depthScale, std::nullopt, maxDepth, out);
        return out;
    }
    if (m.encoding == "32FC1") {
        copyRows(m, 4, where);
        out.width = int(m.width);
        out.height = int(m.height);
        out.meters.resize(size_t(m.width) * m.height);
        for (uint32_t y = 0; y < m.height; ++y) {
            const uint8_t* row = m.data.data() + size_t(y) * m.step;
            for (uint32_t x = 0; x < m.width; ++x) {
                uint8_t b[4];
                std::memcpy(b, row + 4 * x, 4);
                if (m.bigEndian) std::swap(b[0], b[3]), std::swap(b[1], b[2]);
                float v;
                std::memcpy(&v, b, 4);
                if (!std::isfinite(v) || v <= 0 || (maxDepth > 0 && v > maxDepth)) v = 0;
                out.meters[size_t(y) * m.width + x] = v;
            }
        }
        return out;
    }
    throw Error(where + ": depth encoding \"" + m.encoding + "\" is not one vkmesh reads (16UC1 or mono16 in depth units, 32FC1 in metres)");
}

ColorImage colorFromMessage(const ImageMessage& m, const std::string& where) {
    size_t channels = 0;
    int r = 0, g = 1, b = 2;
    if (m.encoding == "rgb8") channels = 3;
    else if (m.encoding == "bgr8") channels = 3, r = 2, b = 0;
    else if (m.encoding == "rgba8") channels = 4;
    else if (m.encoding == "bgra8") channels = 4, r = 2, b = 0;
    else if (m.encoding == "mono8") channels = 1, g = 0, b = 0;
    else
        throw Error(where + ": colour encoding \"" + m.encoding + "\" is not one vkmesh reads (rgb8, bgr8, rgba8, bgra8, mono8)");
    copyRows(m, channels, where);
    ColorImage out;
    out.width = int(m.width);
    out.height = int(m.height);
    out.rgb.resize(size_t(m.width) * m.height * 3);
    for (uint32_t y = 0; y < m.height; ++y) {
        const uint8_t* row = m.data.data() + size_t(y) * m.step;
        uint8_t* dst = out.rgb.data() + size_t(y) * m.width * 3;
        for (uint32_t x = 0; x < m.width; ++x) {
            const uint8_t* p = row + x * channels;
            dst[3 * x] = p[r];
            dst[3 * x + 1] = p[g];
            dst[3 * x + 2] = p[b];
        }
    }
    return out;
}

// Fusion and colour registration project with a pinhole: say so rather than use a distorted image silently as if
// it were rectified (a RealSense depth stream's coefficients are zero; its colour stream's often are not).
void warnIfDistorted(const CameraInfoMessage& info, const std::string& where, const char* camera,
                     std::vector<std::string>& warnings) {
    if (std::any_of(info.d.begin(), info.d.end(), [](double v) { return v != 0.0; }))
        warnings.push_back(where + ": the " + camera + " camera has lens distortion (" + info.distortionModel +
                           "), which vkmesh does not undo: its images are used as if rectified");
}

// fx, fy, cx, cy from a CameraInfo's K (row-major: fx 0 cx / 0 fy cy / 0 0 1), checked.
Intrinsics intrinsicsOf(const CameraInfoMessage& info, const std::string& where) {
    Intrinsics k;
    k.fx = float(info.k[0]);
    k.fy = float(info.k[4]);
    k.cx = float(info.k[2]);
    k.cy = float(info.k[5]);
    k.width = int(info.width);
    k.height = int(info.height);
    if (!(std::isfinite(k.fx) && std::isfinite(k.fy) && std::isfinite(k.cx) && std::isfinite(k.cy)) || !(k.fx > 0) || !(k.fy > 0))
        throw Error(where + ": camera info K = [" + fmt(info.k[0]) + " " + fmt(info.k[1]) + " " + fmt(info.k[2]) + "; " +
                    fmt(info.k[3]) + " " + fmt(info.k[4]) + " " + fmt(info.k[5]) + "; ...] has no usable fx, fy, cx, cy "
                    "(give --intrinsics)");
    return k;
}

// The depth unit as raw units per metre. librealsense stores metres per unit as a float (0.001 is
// 0.0010000000475): a reciprocal within a millionth of an integer is that integer, so the samples convert as a
// folder with that depth_scale would.
double unitsPerMetre(float metresPerUnit) {
    const double perMetre = 1.0 / double(metresPerUnit);
    const double rounded = std::round(perMetre);
    return std::abs(perMetre - rounded) <= 1e-6 * rounded ? rounded : perMetre;
}

std::string formatOf(const Container& c, bool realSense) {
    return c.formatName() + (realSense ? " (librealsense layout)" : "");
}

}  // namespace

DepthImage RecordingSource::loadDepth(size_t i, double depthScale, float maxDepth) const {
    const MessageRef& ref = frames.at(i).depth;
    const std::string where = describe(ref);
    const std::vector<uint8_t> bytes = container->read(ref);
    const ImageMessage m = recording::decodeImage(bytes, container->connections()[ref.connection].serialization, where);
    return depthFromMessage(m, depthScale, maxDepth, where);
}

ColorImage RecordingSource::loadColor(size_t i) const {
    const std::optional<MessageRef>& ref = frames.at(i).color;
    if (!ref) return {};
    const std::string where = describe(*ref);
    const std::vector<uint8_t> bytes = container->read(*ref);
    const ImageMessage m = recording::decodeImage(bytes, container->connections()[ref->connection].serialization, where);
    return colorFromMessage(m, where);
}

Layout readRecording(const fs::path& path, const DatasetOptions& options) {
    auto source = std::make_shared<RecordingSource>();
    source->container = recording::openContainer(path);
    const Container& c = *source->container;
    const std::string file = path.string();
    auto decodeAt = [&](const MessageRef& m, auto decoder) {
        const std::vector<uint8_t> bytes = c.read(m);
        return decoder(bytes, c.connections()[m.connection].serialization, c.describe(m));
    };
    // Each connection's messages in time order.
    std::vector<std::vector<const MessageRef*>> byConnection(c.connections().size());
    for (const MessageRef& m : c.messages()) byConnection.at(m.connection).push_back(&m);

    // --- image topics, told apart by their first message's encoding ---
    Layout layout;
    for (const std::string& w : c.warnings()) layout.warnings.push_back(w);
    // Only ROS 1 and CDR messages can be decoded; a topic in another serialisation (an MCAP channel of JSON or
    // protobuf) is passed over, said once.
    auto decodable = [&](const Connection& conn) {
        if (conn.encoding == "ros1" || conn.encoding == "cdr") return true;
        if (isImageType(conn.type) || isCameraInfoType(conn.type) || isTfType(conn.type))
            layout.warnings.push_back(file + ": topic " + conn.topic + " (" + conn.type + ") is serialised as \"" + conn.encoding +
                                      "\", which vkmesh does not decode (ROS 1 and CDR only); ignored");
        return false;
    };
    std::vector<ImageTopic> images, depthTopics, colorTopics;
    for (const Connection& conn : c.connections()) {
        if (!isImageType(conn.type) || byConnection[conn.id].empty() || !decodable(conn)) continue;
        images.push_back({&conn, decodeAt(*byConnection[conn.id].front(), recording::decodeImage)});
    }
    for (const ImageTopic& t : images) {
        if (kDepthEncodings.count(t.first.encoding) &&
            !nameSays(t.connection->topic, {"infra", "/ir", "_ir", "confidence"}))
            depthTopics.push_back(t);
        else if (kColorEncodings.count(t.first.encoding) && !nameSays(t.connection->topic, {"infra", "/ir", "_ir", "confidence"}))
            colorTopics.push_back(t);
    }
    const ImageTopic* depth = chooseTopic(images, depthTopics, options.depthTopic, "--depth-topic", "depth",
                                          {"depth"}, file);
    if (!depth)
        throw Error(file + ": no depth images: no sensor_msgs/Image topic holds 16UC1, mono16 or 32FC1 images (image topics: " +
                    (images.empty() ? std::string("none") : listTopics(images)) + "); name one with --depth-topic");
    if (!kDepthEncodings.count(depth->first.encoding))
        throw Error(c.describe(*byConnection[depth->connection->id].front()) + ": depth encoding \"" + depth->first.encoding +
                    "\" is not one vkmesh reads (16UC1 or mono16 in depth units, 32FC1 in metres)");
    const ImageTopic* color = chooseTopic(images, colorTopics, options.colorTopic, "--color-topic", "colour",
                                          {"color", "colour", "rgb"}, file);
    if (color == depth) throw Error(file + ": --color-topic and the depth topic are both " + depth->connection->topic);
    if (color && !kColorEncodings.count(color->first.encoding))
        throw Error(c.describe(*byConnection[color->connection->id].front()) + ": colour encoding \"" + color->first.encoding +
                    "\" is not one vkmesh reads (rgb8, bgr8, rgba8, bgra8, mono8)");
    const std::optional<RealSenseStream> rsDepth = realSenseStream(depth->connection->topic);
    const std::optional<RealSenseStream> rsColor = color ? realSenseStream(color->connection->topic) : std::nullopt;

    switch (recording::detectContainer(path)) {
        case recording::ContainerKind::Ros1Bag: layout.kind = rsDepth ? DatasetKind::RealSenseBag : DatasetKind::RosBag; break;
        case recording::ContainerKind::Mcap: layout.kind = DatasetKind::Mcap; break;
        default: layout.kind = DatasetKind::Rosbag2; break;
    }

    // --- camera info: the one named, or the one beside the image topic (longest common topic prefix, its
    // frame id breaking ties) ---
    std::vector<const Connection*> infos;
    for (const Connection& conn : c.connections())
        if (isCameraInfoType(conn.type) && !byConnection[conn.id].empty() && decodable(conn)) infos.push_back(&conn);
    auto infoFor = [&](const ImageTopic& image) -> const Connection* {
        const Connection* best = nullptr;
        size_t bestPrefix = 0;
        for (const Connection* info : infos) {
            const size_t p = commonPrefix(info->topic, image.connection->topic);
            if (p > bestPrefix) best = info, bestPrefix = p;
        }
        // Beside it means sharing the topic's namespace, not only a leading "/".
        return bestPrefix > 1 ? best : nullptr;
    };
    const Connection* depthInfo = nullptr;
    if (!options.infoTopic.empty()) {
        for (const Connection* info : infos)
            if (info->topic == options.infoTopic) depthInfo = info;
        if (!depthInfo) {
            std::string names;
            for (const Connection* info : infos) names += (names.empty() ? "" : ", ") + info->topic;
            throw Error(file + ": --info-topic " + options.infoTopic + " is not a sensor_msgs/CameraInfo topic of this recording; its camera info topics: " +
                        (names.empty() ? std::string("none") : names));
        }
    } else {
        depthInfo = infoFor(*depth);
    }
    if (depthInfo) {
        const MessageRef& m = *byConnection[depthInfo->id].front();
        const CameraInfoMessage info = decodeAt(m, recording::decodeCameraInfo);
        Intrinsics k = intrinsicsOf(info, c.describe(m));
        if (k.width != 0 && (uint32_t(k.width) != depth->first.width || uint32_t(k.height) != depth->first.height))
            throw Error(c.describe(m) + ": camera info for " + std::to_string(k.width) + "x" + std::to_string(k.height) +
                        " images, but the depth images on " + depth->connection->topic + " are " +
                        std::to_string(depth->first.width) + "x" + std::to_string(depth->first.height) +
                        " (choose the depth camera's info with --info-topic)");
        layout.folderIntrinsics = k;
        warnIfDistorted(info, c.describe(m), "depth", layout.warnings);
    } else if (!options.intrinsics) {
        throw Error(file + ": no sensor_msgs/CameraInfo for the depth topic " + depth->connection->topic +
                    (infos.empty() ? std::string(" (the recording has none)") : " (choose one with --info-topic)") +
                    "; or give the camera with --intrinsics fx,fy,cx,cy");
    }

    // --- the depth unit: metres for 32FC1; librealsense's Depth Units option; otherwise ROS's convention
    // (REP 118) for 16-bit depth: millimetres ---
    if (depth->first.encoding == "32FC1") {
        layout.ownDepthScale = 1.0;
    } else {
        layout.ownDepthScale = 1000.0;
        if (rsDepth)
            for (const Connection& conn : c.connections())
                if (conn.topic == rsDepth->sensor + "/option/Depth Units/value" && !byConnection[conn.id].empty()) {
                    const MessageRef& m = *byConnection[conn.id].back();
                    const float units = decodeAt(m, recording::decodeFloat32);
                    if (!(std::isfinite(units) && units > 0))
                        throw Error(c.describe(m) + ": Depth Units = " + fmt(units) + "; expected a positive number of metres");
                    layout.ownDepthScale = unitsPerMetre(units);
                }
    }

    // --- the /tf tree: poses, and the extrinsics between two cameras' frames ---
    TfTree tf;
    for (const Connection& conn : c.connections()) {
        if (!isTfType(conn.type) || !decodable(conn)) continue;
        const bool isStatic = conn.topic == "/tf_static" || conn.topic == "tf_static";
        for (const MessageRef* m : byConnection[conn.id])
            for (const auto& t : decodeAt(*m, recording::decodeTfMessage)) tf.add(t, isStatic, c.describe(*m));
    }
    tf.finish();
    for (const std::string& f : tf.conflicts())
        layout.warnings.push_back(file + ": /tf gives frame " + f + " more than one parent; the first is used");

    // --- the colour camera: its own intrinsics, and extrinsics from librealsense's stream transforms or /tf ---
    if (color) {
        ColorCamera camera;
        camera.intrinsics = layout.folderIntrinsics.value_or(Intrinsics{});
        bool ownCamera = false;
        if (const Connection* colorInfo = infoFor(*color); colorInfo && colorInfo != depthInfo) {
            const MessageRef& m = *byConnection[colorInfo->id].front();
            const CameraInfoMessage info = decodeAt(m, recording::decodeCameraInfo);
            camera.intrinsics = intrinsicsOf(info, c.describe(m));
            warnIfDistorted(info, c.describe(m), "colour", layout.warnings);
            ownCamera = true;
        }
        camera.intrinsics.width = int(color->first.width);
        camera.intrinsics.height = int(color->first.height);
        if (rsDepth && rsColor) {
            // librealsense writes each stream's transform from its extrinsics group's reference to the stream
            // (<stream>/tf/<group>); depth-to-colour is the colour's times the inverse of the depth's, as its
            // playback composes them (playback_device::calc_extrinsic).
            auto streamTransform = [&](const RealSenseStream& s) -> std::optional<std::pair<std::string, Pose>> {
                for (const Connection& conn : c.connections())
                    if (conn.topic.rfind(s.stream + "/tf/", 0) == 0 && conn.type == "geometry_msgs/Transform" &&
                        !byConnection[conn.id].empty()) {
                        const MessageRef& m = *byConnection[conn.id].front();
                        return std::make_pair(conn.topic.substr(s.stream.size() + 4),
                                              poseOf(decodeAt(m, recording::decodeTransform), c.describe(m)));
                    }
                return std::nullopt;
            };
            const auto d = streamTransform(*rsDepth), k = streamTransform(*rsColor);
            if (d && k && d->first == k->first) {
                camera.depthToColor = k->second * inverseRigid(d->second);
                ownCamera = true;
            } else {
                layout.warnings.push_back(file + ": no extrinsics between " + rsDepth->stream + " and " + rsColor->stream +
                                          "; colour is registered as if both cameras had one optical centre");
            }
        } else {
            const std::string depthFrame = frameName(depth->first.header.frameId), colorFrame = frameName(color->first.header.frameId);
            if (!depthFrame.empty() && !colorFrame.empty() && depthFrame != colorFrame) {
                const uint64_t t = stampOf(depth->first.header, *byConnection[depth->connection->id].front());
                const auto d = tf.lookup(depthFrame, t), k = tf.lookup(colorFrame, t);
                if (d && k && d->root == k->root) {
                    camera.depthToColor = inverseRigid(k->rootFromFrame) * d->rootFromFrame;
                    ownCamera = true;
                } else {
                    layout.warnings.push_back(file + ": /tf does not connect the depth frame " + depthFrame + " and the colour frame " +
                                              colorFrame + "; colour is registered as if both cameras had one optical centre");
                }
            }
        }
        if (ownCamera || uint32_t(camera.intrinsics.width) != depth->first.width ||
            uint32_t(camera.intrinsics.height) != depth->first.height)
            layout.colorCamera = camera;
    }

    // --- frames: every depth message in header-time order, its colour the nearest within 20 ms ---
    struct Timed {
        uint64_t t;
        const MessageRef* m;
        std::string frameId;
    };
    auto timedMessages = [&](const Connection& conn) {
        std::vector<Timed> out;
        for (const MessageRef* m : byConnection[conn.id]) {
            // The header from the bytes indexing kept, else from the whole message (a second read of it).
            std::optional<recording::MessageHeader> header =
                recording::decodeLeadingHeader(std::span(m->head.data(), m->headSize), conn.serialization);
            if (!header) header = decodeAt(*m, recording::decodeImage).header;
            out.push_back({stampOf(*header, *m), m, header->frameId});
        }
        std::stable_sort(out.begin(), out.end(), [](const Timed& a, const Timed& b) { return a.t < b.t; });
        return out;
    };
    const std::vector<Timed> depthMessages = timedMessages(*depth->connection);
    const std::vector<Timed> colorMessages = color ? timedMessages(*color->connection) : std::vector<Timed>{};
    const std::string depthFrame = frameName(depth->first.header.frameId);
    const bool tfHasCamera = !depthFrame.empty() && tf.has(depthFrame);
    size_t withoutPose = 0;
    uint64_t previous = 0;
    for (size_t n = 0; n < depthMessages.size(); ++n) {
        const Timed& d = depthMessages[n];
        const std::string where = c.describe(*d.m);
        if (n > 0 && d.t == previous) {
            warnSkipped(layout, where + ": the same time as the message before it; skipped");
            continue;
        }
        previous = d.t;
        FrameInfo f;
        f.timestamp = double(d.t) * 1e-9;
        f.depthPath = path;
        if (tfHasCamera)
            if (const auto pose = tf.lookup(d.frameId.empty() ? depthFrame : d.frameId, d.t); pose && pose->anyDynamic) {
                validatePose(pose->rootFromFrame, where + " (its pose in /tf)");
                f.cameraToWorld = pose->rootFromFrame;
                f.hasPose = true;
            }
        if (!f.hasPose) {
            ++withoutPose;
            if (options.requirePoses && tfHasCamera) {
                warnSkipped(layout, where + ": /tf has no transform of " + depthFrame + " within 20 ms of " +
                                        fmtTime(f.timestamp));
                continue;
            }
        }
        RecordingSource::Frame frame{*d.m, std::nullopt};
        if (!colorMessages.empty()) {
            auto after = std::lower_bound(colorMessages.begin(), colorMessages.end(), d.t,
                                          [](const Timed& a, uint64_t v) { return a.t < v; });
            const Timed* best = nullptr;
            uint64_t gap = std::numeric_limits<uint64_t>::max();
            if (after != colorMessages.end()) best = &*after, gap = after->t - d.t;
            if (after != colorMessages.begin() && d.t - std::prev(after)->t < gap)
                best = &*std::prev(after), gap = d.t - best->t;
            if (best && gap <= kPairingToleranceNs) {
                frame.color = *best->m;
                f.colorPath = path;
                f.colorRecord = c.describe(*best->m);
            } else {
                warnNoColor(layout, where + ": no colour image within 20 ms; fused without colour");
            }
        }
        f.depthRecord = where;
        source->frames.push_back(frame);
        layout.frames.push_back(std::move(f));
    }
    if (depthMessages.empty()) throw Error(file + ": the depth topic " + depth->connection->topic + " has no messages");
    if (options.requirePoses && withoutPose == depthMessages.size())
        throw Error(file + ": no camera poses: " +
                    (tfHasCamera ? "/tf has no transform of " + depthFrame + " near any depth frame's time"
                                 : "/tf has no transform of the depth frame " + (depthFrame.empty() ? std::string("(none named)") : depthFrame)) +
                    " (" + kTrackingHint + ")");
    if (options.requirePoses) summariseSkipped(layout, depthMessages.size(), "no pose in /tf within 20 ms");
    else summariseFramesWithoutPose(layout, "no pose in /tf");
    if (layout.frames.empty()) throw Error(file + ": no depth frame is usable");

    layout.description = formatOf(c, rsDepth.has_value()) + ", depth " + depth->connection->topic + " (" + depth->first.encoding + ")" +
                         (color ? ", colour " + color->connection->topic + " (" + color->first.encoding + ")" : std::string(", no colour")) +
                         (depthInfo ? ", camera info " + depthInfo->topic : std::string());
    layout.recording = source;
    return layout;
}

}  // namespace vkmesh::datasets
