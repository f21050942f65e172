#include "vk/check.h"

#include <string>

namespace vkmesh::vk {

const char* resultName(VkResult result) {
    switch (result) {
#define VKM_NAME(r) \
    case r:         \
        return #r;
        VKM_NAME(VK_SUCCESS)
        VKM_NAME(VK_NOT_READY)
        VKM_NAME(VK_TIMEOUT)
        VKM_NAME(VK_INCOMPLETE)
        VKM_NAME(VK_ERROR_OUT_OF_HOST_MEMORY)
        VKM_NAME(VK_ERROR_OUT_OF_DEVICE_MEMORY)
        VKM_NAME(VK_ERROR_INITIALIZATION_FAILED)
        VKM_NAME(VK_ERROR_DEVICE_LOST)
        VKM_NAME(VK_ERROR_MEMORY_MAP_FAILED)
        VKM_NAME(VK_ERROR_LAYER_NOT_PRESENT)
        VKM_NAME(VK_ERROR_EXTENSION_NOT_PRESENT)
        VKM_NAME(VK_ERROR_FEATURE_NOT_PRESENT)
        VKM_NAME(VK_ERROR_INCOMPATIBLE_DRIVER)
        VKM_NAME(VK_ERROR_TOO_MANY_OBJECTS)
        VKM_NAME(VK_ERROR_FORMAT_NOT_SUPPORTED)
        VKM_NAME(VK_ERROR_FRAGMENTED_POOL)
        VKM_NAME(VK_ERROR_OUT_OF_POOL_MEMORY)
        VKM_NAME(VK_ERROR_INVALID_SHADER_NV)
        VKM_NAME(VK_ERROR_UNKNOWN)
#undef VKM_NAME
        default:
            return "VkResult(unknown)";
    }
}

void check(VkResult result, const char* call) {
    if (result == VK_SUCCESS) return;
    std::string message = std::string(call) + " failed: " + resultName(result) + " (" + std::to_string(result) + ")";
    if (result == VK_ERROR_OUT_OF_DEVICE_MEMORY || result == VK_ERROR_OUT_OF_HOST_MEMORY)
        message += "; lower the capacities (--blocks) or choose another device (--device)";
    if (result == VK_ERROR_INCOMPATIBLE_DRIVER)
        message += "; no Vulkan driver found: install mesa-vulkan-drivers (lavapipe) or your GPU's driver";
    throw Error(message);
}

}  // namespace vkmesh::vk
