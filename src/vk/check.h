// VkResult -> exception naming the failed call, so that callers and tests can react (no exit() in a
// library).
#pragma once

#include <vulkan/vulkan.h>

#include "core/types.h"

namespace vkmesh::vk {

const char* resultName(VkResult result);

// Throws vkmesh::Error("<call> failed: VK_ERROR_...") unless result is VK_SUCCESS.
void check(VkResult result, const char* call);

}  // namespace vkmesh::vk

#define VKM_CHECK(call) ::vkmesh::vk::check((call), #call)
