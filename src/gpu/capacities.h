// Capacities of the GPU volume (docs/MESH.md, "Capacities"): helpers shared by the volume (src/gpu/gpu_volume.cpp)
// and its growth policy (src/gpu/capacities.cpp). Internal to the library.
#pragma once

#include <cstdint>

#include "gpu/gpu_volume.h"

namespace vkmesh::gpu {

uint32_t nextPowerOfTwo(uint32_t v);
// The largest device-local heap: where vkmesh's buffers live.
uint64_t deviceLocalHeapBytes(const vk::Context& context);
// The per-frame lists a configuration implies.
FrameListCapacities listCapacities(const GpuVolumeConfig& c);

}  // namespace vkmesh::gpu
