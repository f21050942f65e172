#include "vk/graphics_resources.h"

#include <cstdint>
#include <map>
#include <span>

#include "core/types.h"
#include "vk/check.h"

namespace vkmesh::shaders {
// Every shaders_render/* file as SPIR-V words, by file name ("mesh.vert"); see cmake/EmbedShaders.cmake.
const std::map<std::string, std::span<const uint32_t>>& graphics();
}  // namespace vkmesh::shaders

namespace vkmesh::vk {

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

void createAttachmentImage(const vk::Context& context, int width, int height, VkFormat format, VkImageUsageFlags usage,
                           VkImageAspectFlags aspect, VkImage& image, VkDeviceMemory& memory, VkImageView& view) {
    VkDevice device = context.device();
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {static_cast<uint32_t>(width), static_cast<uint32_t>(height), 1};
    info.mipLevels = 1;
    info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    VKM_CHECK(vkCreateImage(device, &info, nullptr, &image));
    VkMemoryRequirements req{};
    vkGetImageMemoryRequirements(device, image, &req);
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = context.findMemoryType(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    VKM_CHECK(vkAllocateMemory(device, &alloc, nullptr, &memory));
    VKM_CHECK(vkBindImageMemory(device, image, memory, 0));
    VkImageViewCreateInfo viewInfo{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    viewInfo.image = image;
    viewInfo.viewType = VK_IMAGE_VIEW_TYPE_2D;
    viewInfo.format = format;
    viewInfo.subresourceRange = {aspect, 0, 1, 0, 1};
    VKM_CHECK(vkCreateImageView(device, &viewInfo, nullptr, &view));
}

}  // namespace vkmesh::vk
