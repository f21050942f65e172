// What the two users of the graphics pipeline (the mesh renderer and tracking's model maps) both create: the
// embedded shaders of shaders_render/ (SPIR-V at build time: cmake/EmbedShaders.cmake,
// vkmesh_embed_graphics_shaders) and 2D attachment images.
#pragma once

#include <vulkan/vulkan.h>

#include <string>

#include "vk/context.h"

namespace vkmesh::vk {

// A shader module of the embedded shader `name` ("mesh.vert"); the caller destroys it. Throws Error when no
// shader of that name is embedded, VKM_CHECK's error when Vulkan fails.
VkShaderModule createGraphicsShaderModule(VkDevice device, const std::string& name);

// A width x height device-local 2D image (one mip level, one layer, optimal tiling) with its memory and a view
// of `aspect`; the caller destroys all three, also when this throws part way (handles it did not create stay
// VK_NULL_HANDLE).
void createAttachmentImage(const vk::Context& context, int width, int height, VkFormat format, VkImageUsageFlags usage,
                           VkImageAspectFlags aspect, VkImage& image, VkDeviceMemory& memory, VkImageView& view);

}  // namespace vkmesh::vk
