#include "vk/shader_registry.h"

#include "vk/check.h"
#include "vk/pipeline.h"

namespace vkmesh::shaders {

std::string computeShaderKey(const std::string& shaderName, bool int64Atomics) {
    return int64Atomics ? shaderName : shaderName + "@hash32";
}

std::span<const uint32_t> computeShader(const std::string& shaderName, bool int64Atomics) {
    const auto& table = all();
    auto it = table.find(computeShaderKey(shaderName, int64Atomics));
    if (it == table.end())
        throw Error("No embedded shader named '" + shaderName + "'" + (int64Atomics ? "" : " in the 32-bit hash build"));
    return it->second;
}

std::span<const uint32_t> computeShaderFor(const vk::Context& context, const std::string& shaderName) {
    return computeShader(shaderName, context.int64Atomics());
}

}  // namespace vkmesh::shaders
