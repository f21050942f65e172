// Internal to src/io/recordings: the chunk decompressions of ROS 1 bags and MCAP, through Debian's libraries
// (libbz2, liblz4's frame format, libzstd).
#pragma once

#include "core/fuzzing.h"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace vkmesh::io::recording::detail {

// The most a chunk may declare it decompresses to. ROS 1 chunks are ~768 KB by default and MCAP's 4 MB, but a
// chunk holds at least one whole message (a 4K 16-bit image is 16 MB, a point cloud more): 1 GiB leaves room
// for those while refusing a hostile 4 GB size outright.
// The fuzz targets use 64 MiB: a fuzzer-made decompression bomb of a gigabyte would only report a timeout
// (core/fuzzing.h).
inline uint64_t maxChunkBytes() { return fuzzing::active() ? uint64_t(64) << 20 : uint64_t(1) << 30; }

// `in` decompressed with `compression` ("none" or "" for stored, "bz2", "lz4" (LZ4 frame format, as ROS's
// roslz4 and MCAP write it), "zstd"); it must come to exactly `expectedSize` bytes (the chunk header's size).
// The output grows with what the decompressor produces rather than being allocated at `expectedSize` up
// front, so a small hostile file cannot make it allocate a gigabyte. Throws Error starting with `where`.
std::vector<uint8_t> decompress(std::string_view compression, std::string_view in, uint64_t expectedSize,
                                const std::string& where);

}  // namespace vkmesh::io::recording::detail
