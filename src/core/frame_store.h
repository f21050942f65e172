// The frame store: every fused frame exactly as it was fused (depth bit for bit, colour, pose, intrinsics,
// timestamp), so that a frame can later be subtracted from the TSDF and fused again at a corrected pose
// (exact de-integration). Frames are held losslessly compressed (zstd: the depth floats as they are, the colour
// as planes of row differences; frame_store.cpp says why) in host memory up to a byte budget; past it they go to a spill folder, or, without one,
// add() throws rather than drop a frame. save()/load() keep the whole store in one .vkframes file, tied to
// the map it belongs to by a map id.
//
// File layout (little-endian):
//   header   "VKFRAMES" (8 bytes), u32 version (1), u64 map id, u64 frame count
//   records  in ascending frame index, each 176 bytes of header and then its payload:
//            u32 index, f64 timestamp, f32 fx fy cx cy, i32 width height (of the intrinsics and the depth
//            image alike), f64 pose[16] (camera-to-world, row-major), u32 depth payload bytes, u32 colour
//            payload bytes (0 = no colour), u32 CRC-32 (map::crc32) of the record's previous 172 bytes
//            followed by its payload;
//            payload: the depth's zstd frame (width x height f32, row-major), then the colour's (three planes
//            R, G, B of width x height bytes, each byte the difference modulo 256 from its left neighbour, the
//            first of a row from 0).
//
// Not synchronised: const members may run concurrently with each other, anything else needs the store alone.
#pragma once

#include "core/types.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace vkmesh {

struct StoredFrame {
    uint32_t index = 0;            // the frame's index in the fused sequence (the key: unique in a store)
    double timestamp = 0;          // the dataset's timestamp (TUM-format trajectories match frames by it)
    Intrinsics intrinsics;         // width and height equal the depth image's
    Pose pose = Pose::Identity();  // camera-to-world, as fused
    DepthImage depth;              // as fused, bit for bit
    ColorImage color;              // as fused; empty when the frame had none
};

struct FrameStoreOptions {
    size_t memoryBudgetBytes = size_t(1) << 30;  // compressed bytes held in memory
    std::string spillFolder;                     // frames past the budget go here; "" = none: add() throws instead
    int zstdLevel = 3;                           // see bench/frame_store_bytes.cpp for the bytes and milliseconds of others
};

struct FrameStoreStats {
    size_t frames = 0, framesInMemory = 0, framesSpilled = 0;
    size_t rawBytes = 0;         // depth (4 bytes a pixel) and colour (3) uncompressed
    size_t compressedBytes = 0;  // bytesInMemory + bytesOnDisk
    size_t bytesInMemory = 0, bytesOnDisk = 0;
};

class FrameStore {
public:
    explicit FrameStore(FrameStoreOptions options = {});
    // Removes its spill files (the store owns them); a moved-from store owns none.
    ~FrameStore();
    FrameStore(FrameStore&& other) noexcept;
    FrameStore& operator=(FrameStore&& other) noexcept;
    FrameStore(const FrameStore&) = delete;
    FrameStore& operator=(const FrameStore&) = delete;

    // Compresses and keeps `frame`: in memory while the budget allows, else in the spill folder. Throws Error
    // if the index is already there, the sizes disagree (depth samples vs width x height, colour vs depth,
    // intrinsics vs depth), an image is empty or larger than 16384 per side / 64 Mpixel, the pose is not
    // finite, or the frame is over the budget and there is no spill folder.
    void add(const StoredFrame& frame);
    bool contains(uint32_t index) const;
    // Decompresses the frame (reading its spill file if spilled). Throws Error naming the index if unknown,
    // or the file if a spill file is missing or corrupt.
    StoredFrame get(uint32_t index) const;
    // Without decompressing anything.
    const Pose& pose(uint32_t index) const;
    double timestamp(uint32_t index) const;
    // After the frame was fused again at a corrected pose. Throws Error if unknown or not finite.
    void setPose(uint32_t index, const Pose& pose);
    // Moves every frame of `other` here, under its index + indexOffset, as it is (compressed: nothing is
    // recompressed; a frame spilled there is read back and kept here as add() keeps one). Throws Error before
    // anything moves if a new index is already here or passes 2^32 - 1; past the budget without a spill folder,
    // as add() does (the frames moved so far stay here). `other` is left empty.
    void absorb(FrameStore&& other, uint32_t indexOffset = 0);
    std::vector<uint32_t> indices() const;  // ascending
    size_t size() const;
    FrameStoreStats stats() const;

    // One file holding every frame (written to `path`.tmp and renamed, so a crash never leaves half a file).
    void save(const std::string& path, uint64_t mapId) const;
    // Reads a file written by save(); frames past options' budget spill as in add(). Throws Error naming the
    // path and the problem: not a frame store (magic), a newer version, a file of another map (map id),
    // a truncated file or a CRC mismatch (naming the frame record), a corrupt zstd payload, trailing bytes.
    static FrameStore load(const std::string& path, uint64_t expectedMapId, FrameStoreOptions options = {});
    // The map id in a file's header, reading nothing else (same errors for the header as load()).
    static uint64_t mapIdOf(const std::string& path);

private:
    struct Entry {
        double timestamp = 0;
        Intrinsics intrinsics;
        Pose pose = Pose::Identity();
        uint32_t depthBytes = 0, colorBytes = 0;  // the two zstd frames' sizes; colorBytes 0 = no colour
        uint32_t payloadCrc = 0;                  // map::crc32 of the payload, checked when a spill file is read
        std::string payload;                      // depth frame then colour frame; empty while spilled
        bool spilled = false;
        size_t payloadBytes() const { return size_t(depthBytes) + colorBytes; }
    };
    const Entry& entry(uint32_t index) const;
    // Keeps `e` under `index` (not yet there), in memory or spilled.
    void insert(uint32_t index, Entry&& e);
    std::filesystem::path spillFile(uint32_t index) const;
    std::string payloadOf(uint32_t index, const Entry& e) const;
    void removeSpillFolder() noexcept;

    FrameStoreOptions options_;
    std::map<uint32_t, Entry> frames_;
    size_t bytesInMemory_ = 0, bytesOnDisk_ = 0, rawBytes_ = 0;
    // This store's own folder inside options_.spillFolder, made at the first spill ("" until then).
    std::filesystem::path spillDir_;
};

}  // namespace vkmesh
