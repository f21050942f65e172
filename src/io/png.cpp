#include "io/png.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <string>

#include "core/types.h"

namespace vkmesh::io {

namespace {

// `subject` names the file in the message ("depth image 'a.png'" or just the path).
void encode(const std::filesystem::path& path, const cv::Mat& image, const std::string& subject) {
    bool written = false;
    try {
        written = cv::imwrite(path.string(), image);
    } catch (const cv::Exception& e) {
        throw Error("cannot write " + subject + ": " + e.what());
    }
    if (!written) throw Error("cannot write " + subject);
}

}  // namespace

void writeDepthPng(const std::filesystem::path& path, int width, int height, const std::vector<uint16_t>& pixels) {
    if (width <= 0 || height <= 0 || pixels.size() != size_t(width) * size_t(height))
        throw Error("cannot write depth image '" + path.string() + "': " + std::to_string(pixels.size()) +
                    " pixels for " + std::to_string(width) + "x" + std::to_string(height));
    cv::Mat raw(height, width, CV_16UC1);
    for (int y = 0; y < height; ++y) {
        auto* row = raw.ptr<uint16_t>(y);
        for (int x = 0; x < width; ++x) row[x] = pixels[size_t(y) * size_t(width) + size_t(x)];
    }
    encode(path, raw, "depth image '" + path.string() + "'");
}

void writePng(const std::filesystem::path& path, const Image& image) {
    if (image.width <= 0 || image.height <= 0 || image.rgba.size() != size_t(image.width) * image.height * 4)
        throw Error("cannot write " + path.string() + ": the image is empty or inconsistent");
    cv::Mat bgr(image.height, image.width, CV_8UC3);
    for (int y = 0; y < image.height; ++y) {
        uint8_t* row = bgr.ptr<uint8_t>(y);
        for (int x = 0; x < image.width; ++x) {
            const uint8_t* p = image.pixel(x, y);
            row[3 * x + 0] = p[2];
            row[3 * x + 1] = p[1];
            row[3 * x + 2] = p[0];
        }
    }
    encode(path, bgr, path.string());
}

void writeColorPng(const std::filesystem::path& path, const ColorImage& image) {
    if (image.width <= 0 || image.height <= 0 || image.rgb.size() != size_t(image.width) * image.height * 3)
        throw Error("cannot write colour image '" + path.string() + "': the image is empty or inconsistent");
    cv::Mat bgr(image.height, image.width, CV_8UC3);
    for (int y = 0; y < image.height; ++y) {
        uint8_t* row = bgr.ptr<uint8_t>(y);
        for (int x = 0; x < image.width; ++x) {
            const uint8_t* p = image.at(x, y);
            row[3 * x + 0] = p[2];
            row[3 * x + 1] = p[1];
            row[3 * x + 2] = p[0];
        }
    }
    encode(path, bgr, "colour image '" + path.string() + "'");
}

}  // namespace vkmesh::io
