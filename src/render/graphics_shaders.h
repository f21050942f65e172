// The graphics shaders of shaders_render/ (the mesh renderer's and tracking's model maps), embedded as SPIR-V
// at build time (cmake/EmbedShaders.cmake, vkmesh_embed_graphics_shaders).
#pragma once

#include <vulkan/vulkan.h>

#include <string>

namespace vkmesh::render {

// A shader module of the embedded shader `name` ("mesh.vert"); the caller destroys it. Throws Error when no
// shader of that name is embedded, VKM_CHECK's error when Vulkan fails.
VkShaderModule createGraphicsShaderModule(VkDevice device, const std::string& name);

}  // namespace vkmesh::render
