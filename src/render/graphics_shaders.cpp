#include "render/graphics_shaders.h"

#include <cstdint>
#include <map>
#include <span>

#include "core/types.h"
#include "vk/check.h"

namespace vkmesh::shaders {
// Every shaders_render/* file as SPIR-V words, by file name ("mesh.vert"); see cmake/EmbedShaders.cmake.
const std::map<std::string, std::span<const uint32_t>>& graphics();
}  // namespace vkmesh::shaders

namespace vkmesh::render {

VkShaderModule createGraphicsShaderModule(VkDevice device, const std::string& name) {
    const auto& table = shaders::graphics();
    auto it = table.find(name);
    if (it == table.end()) throw Error("graphics shader '" + name + "' is not embedded in this build");
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    info.codeSize = it->second.size() * sizeof(uint32_t);
    info.pCode = it->second.data();
    VkShaderModule module = VK_NULL_HANDLE;
    VKM_CHECK(vkCreateShaderModule(device, &info, nullptr, &module));
    return module;
}

}  // namespace vkmesh::render
