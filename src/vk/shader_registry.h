// Which embedded SPIR-V a compute pipeline uses on a device. Every compute shader is compiled twice
// (cmake/EmbedShaders.cmake): the plain build uses 64-bit integers and a 64-bit atomicCompSwap for the
// block hash; the "@hash32" build (-DVKMESH_HASH32) uses 32-bit atomics only and no 64-bit type at all,
// for devices without shaderInt64 or shaderBufferInt64Atomics (docs/HASH.md). Every pipeline of a
// volume must come from the same build: the two lay out the hash keys differently.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "vk/context.h"

namespace vkmesh::shaders {

// The registry key of `shaderName`'s build for a device with (int64Atomics) or without 64-bit atomics.
std::string computeShaderKey(const std::string& shaderName, bool int64Atomics);
// The SPIR-V of `shaderName` in the build that `context`'s device runs (Context::int64Atomics()).
// Throws vkmesh::Error when no such shader is embedded.
std::span<const uint32_t> computeShaderFor(const vk::Context& context, const std::string& shaderName);
std::span<const uint32_t> computeShader(const std::string& shaderName, bool int64Atomics);

}  // namespace vkmesh::shaders
