// The decoders of depth and colour images held in memory (io/parsers.h), with the size checks made on the
// file's header before a decoder allocates anything; and the one conversion of raw depth samples to metres.
#include "io/parsers.h"

#include <opencv2/imgcodecs.hpp>

#include <cstring>
#include <limits>
#include <tuple>

namespace vkmesh::io {

namespace {

std::string describeType(const cv::Mat& m) {
    static const char* depthNames[] = {"8-bit unsigned", "8-bit signed", "16-bit unsigned", "16-bit signed",
                                       "32-bit signed",  "32-bit float", "64-bit float",    "16-bit float"};
    int d = m.depth();
    std::string s = (d >= 0 && d < 8) ? depthNames[d] : "unknown depth " + std::to_string(d);
    int c = m.channels();
    return s + ", " + std::to_string(c) + (c == 1 ? " channel" : " channels");
}

std::string describePng(int bitDepth, int colorType) {
    std::string kind;
    switch (colorType) {
        case 0: kind = "grayscale, 1 channel"; break;
        case 2: kind = "RGB, 3 channels"; break;
        case 3: kind = "palette colour, 3 channels"; break;
        case 4: kind = "grayscale + alpha, 2 channels"; break;
        case 6: kind = "RGBA, 4 channels"; break;
        default: kind = "unknown colour type " + std::to_string(colorType); break;
    }
    return std::to_string(bitDepth) + "-bit " + kind;
}


}  // namespace


cv::Mat decodeDepthPng(std::string_view bytes, const std::string& source) {
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (bytes.size() < 8 || std::memcmp(bytes.data(), signature, 8) != 0)
        throw Error("depth image " + source + " is not a PNG file" +
                    (bytes.empty() ? std::string(" (it is empty)") : std::string(" (no PNG signature)")));
    // The header chunk (IHDR) must come first: length at byte 8, type at 12, then width, height, bit depth,
    // colour type. Checked here, before the decoder allocates anything.
    if (bytes.size() < 8 + 8 + 13 || std::memcmp(bytes.data() + 12, "IHDR", 4) != 0)
        throw Error("depth image " + source + " is truncated or corrupt (no PNG header chunk; " +
                    std::to_string(bytes.size()) + " bytes)");
    auto be32 = [&](size_t o) {
        return uint32_t(uint8_t(bytes[o])) << 24 | uint32_t(uint8_t(bytes[o + 1])) << 16 |
               uint32_t(uint8_t(bytes[o + 2])) << 8 | uint32_t(uint8_t(bytes[o + 3]));
    };
    const uint32_t w = be32(16), h = be32(20);
    const int bitDepth = uint8_t(bytes[24]), colorType = uint8_t(bytes[25]);
    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    if (w == 0 || h == 0) throw Error("depth image " + source + " is corrupt: its header says " + size + " pixels");
    if (w > kMaxDepthImageSide || h > kMaxDepthImageSide || uint64_t(w) * h > kMaxDepthImagePixels)
        throw Error("depth image " + source + " claims " + size + " pixels, more than vkmesh accepts (" +
                    std::to_string(kMaxDepthImageSide) + " per side, " + std::to_string(kMaxDepthImagePixels >> 20) +
                    " Mpixel); the file is corrupt or not a depth image");
    if (bitDepth != 16 || colorType != 0)
        throw Error("depth image " + source + " is " + describePng(bitDepth, colorType) + " (" + size +
                    "); expected 16-bit unsigned, 1 channel (a 16-bit grayscale PNG)");
    if (bytes.size() > size_t(std::numeric_limits<int>::max()))
        throw Error("depth image " + source + " is " + std::to_string(bytes.size()) + " bytes, too large to be a depth image");
    cv::Mat img;
    try {
        const cv::Mat buffer(1, int(bytes.size()), CV_8U, const_cast<char*>(bytes.data()));
        img = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
        throw Error("cannot decode depth image " + source + ": " + e.what());
    }
    if (img.empty()) throw Error("cannot decode depth image " + source + " (truncated or corrupt)");
    if (img.type() != CV_16UC1)
        throw Error("depth image " + source + " is " + describeType(img) + " (" + std::to_string(img.cols) + "x" +
                    std::to_string(img.rows) + "); expected 16-bit unsigned, 1 channel");
    if (img.cols != int(w) || img.rows != int(h))
        throw Error("depth image " + source + " decodes to " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                    " but its header says " + size);
    return img;
}

void rawDepthToMeters(const uint16_t* raw, int width, int height, size_t rowStride, double depthScale,
                      std::optional<uint16_t> invalidRaw, float maxDepth, DepthImage& out) {
    out.width = width;
    out.height = height;
    out.meters.resize(static_cast<size_t>(width) * height);
    const uint16_t invalid = invalidRaw.value_or(0);
    for (int y = 0; y < height; ++y) {
        const uint16_t* row = raw + static_cast<size_t>(y) * rowStride;
        float* dst = out.meters.data() + static_cast<size_t>(y) * width;
        for (int x = 0; x < width; ++x) {
            uint16_t v = row[x];
            float m = (v == 0 || v == invalid) ? 0.0f : static_cast<float>(v / depthScale);
            if (maxDepth > 0 && m > maxDepth) m = 0.0f;
            dst[x] = m;
        }
    }
}

DepthImage rawDepthToMeters(const cv::Mat& raw, double depthScale, std::optional<uint16_t> invalidRaw, float maxDepth) {
    DepthImage out;
    rawDepthToMeters(raw.ptr<uint16_t>(0), raw.cols, raw.rows, raw.step1(), depthScale, invalidRaw, maxDepth, out);
    return out;
}

namespace {

uint32_t be16(std::string_view b, size_t o) { return uint32_t(uint8_t(b[o])) << 8 | uint32_t(uint8_t(b[o + 1])); }

// Width and height from a JPEG's frame header (SOFn), found by walking the marker segments before the scan;
// nothing when the segments are corrupt or end first.
std::optional<std::pair<uint32_t, uint32_t>> jpegSize(std::string_view b) {
    size_t o = 2;  // after the SOI marker FF D8
    while (o + 4 <= b.size()) {
        if (uint8_t(b[o]) != 0xFF) return std::nullopt;
        const uint8_t marker = uint8_t(b[o + 1]);
        if (marker == 0xFF) {  // fill byte
            ++o;
            continue;
        }
        if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {  // no length
            o += 2;
            continue;
        }
        const uint32_t length = be16(b, o + 2);
        if (length < 2) return std::nullopt;
        const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
        if (sof) {
            if (o + 9 > b.size()) return std::nullopt;
            return std::make_pair(be16(b, o + 7), be16(b, o + 5));
        }
        if (marker == 0xDA || marker == 0xD9) return std::nullopt;  // scan or end before any frame header
        o += 2 + length;
    }
    return std::nullopt;
}

}  // namespace

ColorImage decodeColorImage(std::string_view bytes, const std::string& source) {
    static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    const bool isPng = bytes.size() >= 8 && std::memcmp(bytes.data(), png, 8) == 0;
    const bool isJpeg = bytes.size() >= 3 && uint8_t(bytes[0]) == 0xFF && uint8_t(bytes[1]) == 0xD8 && uint8_t(bytes[2]) == 0xFF;
    if (!isPng && !isJpeg)
        throw Error("colour image " + source + " is neither a PNG nor a JPEG file" +
                    (bytes.empty() ? std::string(" (it is empty)") : std::string(" (no PNG or JPEG signature)")));
    // The size from the header, checked before the decoder allocates anything (as for depth).
    uint32_t w = 0, h = 0;
    if (isPng) {
        if (bytes.size() < 8 + 8 + 13 || std::memcmp(bytes.data() + 12, "IHDR", 4) != 0)
            throw Error("colour image " + source + " is truncated or corrupt (no PNG header chunk; " +
                        std::to_string(bytes.size()) + " bytes)");
        w = be16(bytes, 16) << 16 | be16(bytes, 18);
        h = be16(bytes, 20) << 16 | be16(bytes, 22);
        const int bitDepth = uint8_t(bytes[24]), colorType = uint8_t(bytes[25]);
        if (bitDepth == 16)
            throw Error("colour image " + source + " is " + describePng(bitDepth, colorType) +
                        "; expected 8 bits per channel (is it a depth image?)");
    } else {
        const auto size = jpegSize(bytes);
        if (!size) throw Error("colour image " + source + " is a truncated or corrupt JPEG (no frame header)");
        std::tie(w, h) = *size;
    }
    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    if (w == 0 || h == 0) throw Error("colour image " + source + " is corrupt: its header says " + size + " pixels");
    if (w > kMaxDepthImageSide || h > kMaxDepthImageSide || uint64_t(w) * h > kMaxDepthImagePixels)
        throw Error("colour image " + source + " claims " + size + " pixels, more than vkmesh accepts (" +
                    std::to_string(kMaxDepthImageSide) + " per side, " + std::to_string(kMaxDepthImagePixels >> 20) +
                    " Mpixel)");
    if (bytes.size() > size_t(std::numeric_limits<int>::max()))
        throw Error("colour image " + source + " is " + std::to_string(bytes.size()) + " bytes, too large");
    cv::Mat img;
    try {
        const cv::Mat buffer(1, int(bytes.size()), CV_8U, const_cast<char*>(bytes.data()));
        // UNCHANGED: no EXIF rotation (the image must stay on the depth camera's grid), no silent 16 -> 8 bits.
        img = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
        throw Error("cannot decode colour image " + source + ": " + e.what());
    }
    if (img.empty()) throw Error("cannot decode colour image " + source + " (truncated or corrupt)");
    if (img.depth() != CV_8U || (img.channels() != 1 && img.channels() != 3 && img.channels() != 4))
        throw Error("colour image " + source + " is " + describeType(img) + " (" + std::to_string(img.cols) + "x" +
                    std::to_string(img.rows) + "); expected 8-bit with 1, 3 or 4 channels");
    ColorImage out;
    out.width = img.cols;
    out.height = img.rows;
    out.rgb.resize(size_t(img.cols) * img.rows * 3);
    const int c = img.channels();
    for (int y = 0; y < img.rows; ++y) {
        const uint8_t* row = img.ptr<uint8_t>(y);
        uint8_t* dst = out.rgb.data() + size_t(y) * img.cols * 3;
        for (int x = 0; x < img.cols; ++x, dst += 3) {
            const uint8_t* p = row + size_t(x) * c;
            if (c == 1) {
                dst[0] = dst[1] = dst[2] = p[0];
            } else {  // OpenCV's order is B, G, R (, A)
                dst[0] = p[2];
                dst[1] = p[1];
                dst[2] = p[0];
            }
        }
    }
    return out;
}

}  // namespace vkmesh::io
