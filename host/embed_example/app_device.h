// The Vulkan setup of an application that embeds vkmesh: its own instance (with the validation layer,
// synchronisation validation and its own messenger when asked), the first device vkmesh can run on, one
// queue family, a device created with the features vkmesh needs. vkmesh only borrows these objects.
// Used by the embedding example (embed_example.cpp) and by tests/gpu/test_embedding.cpp.
#pragma once

#include <vulkan/vulkan.h>

#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/types.h"
#include "vk/check.h"
#include "vk/context.h"

namespace vkmesh::example {

class AppDevice {
public:
    explicit AppDevice(bool validation) {
        createInstance(validation);
        try {
            createDevice();
        } catch (...) {
            destroy();
            throw;
        }
    }
    ~AppDevice() { destroy(); }
    AppDevice(const AppDevice&) = delete;
    AppDevice& operator=(const AppDevice&) = delete;

    // What vkmesh is given.
    vk::ExternalDevice external() const { return {instance, physical, device, queueFamily, 0}; }
    // Validation messages since the last call (always empty without validation).
    std::vector<std::string> takeMessages() {
        std::lock_guard<std::mutex> lock(mutex_);
        return std::exchange(messages_, {});
    }

    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    uint32_t queueFamily = 0;

private:
    void createInstance(bool validation) {
        VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
        app.pApplicationName = "vkmesh embedding example";
        app.apiVersion = VK_API_VERSION_1_2;   // vkmesh needs Vulkan 1.2
        const char* layers[] = {"VK_LAYER_KHRONOS_validation"};
        const char* extensions[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME, VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME};
        VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
        VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
        features.enabledValidationFeatureCount = 1;
        features.pEnabledValidationFeatures = enables;
        VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
        info.pNext = validation ? &features : nullptr;
        info.pApplicationInfo = &app;
        info.enabledLayerCount = validation ? 1 : 0;
        info.ppEnabledLayerNames = layers;
        info.enabledExtensionCount = validation ? 2 : 0;
        info.ppEnabledExtensionNames = extensions;
        vk::check(vkCreateInstance(&info, nullptr, &instance), "vkCreateInstance");
        if (!validation) return;
        VkDebugUtilsMessengerCreateInfoEXT messengerInfo{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        messengerInfo.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
        messengerInfo.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                                    VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
        messengerInfo.pfnUserCallback = &AppDevice::onMessage;
        messengerInfo.pUserData = this;
        auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(vkGetInstanceProcAddr(instance, "vkCreateDebugUtilsMessengerEXT"));
        if (!create || create(instance, &messengerInfo, nullptr, &messenger_) != VK_SUCCESS) {
            destroy();
            throw Error("cannot create the validation messenger");
        }
    }

    void createDevice() {
        uint32_t n = 0;
        vkEnumeratePhysicalDevices(instance, &n, nullptr);
        std::vector<VkPhysicalDevice> devices(n);
        vkEnumeratePhysicalDevices(instance, &n, devices.data());
        for (VkPhysicalDevice d : devices)
            if (vk::Context::describeDevice(d).suitable) {
                physical = d;
                break;
            }
        if (!physical) throw Error("no Vulkan device can run vkmesh (see `vkmesh devices`)");
        queueFamily = vk::Context::chooseQueueFamily(physical);
        float priority = 1.0f;
        VkDeviceQueueCreateInfo queueInfo{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        queueInfo.queueFamilyIndex = queueFamily;
        queueInfo.queueCount = 1;
        queueInfo.pQueuePriorities = &priority;
        VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
        VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
        features.pNext = &f12;
        vk::Context::enableRequiredFeatures(features, f12);   // plus whatever the application itself needs
        VkDeviceCreateInfo deviceInfo{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        deviceInfo.pNext = &features;
        deviceInfo.queueCreateInfoCount = 1;
        deviceInfo.pQueueCreateInfos = &queueInfo;
        vk::check(vkCreateDevice(physical, &deviceInfo, nullptr, &device), "vkCreateDevice");
    }

    void destroy() {
        if (device) vkDestroyDevice(device, nullptr);
        if (messenger_) {
            auto destroyMessenger = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
            if (destroyMessenger) destroyMessenger(instance, messenger_, nullptr);
        }
        if (instance) vkDestroyInstance(instance, nullptr);
        device = VK_NULL_HANDLE;
        messenger_ = VK_NULL_HANDLE;
        instance = VK_NULL_HANDLE;
    }

    static VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT, VkDebugUtilsMessageTypeFlagsEXT,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
        auto* self = static_cast<AppDevice*>(user);
        std::lock_guard<std::mutex> lock(self->mutex_);
        self->messages_.push_back(data && data->pMessage ? data->pMessage : "");
        return VK_FALSE;
    }

    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    std::mutex mutex_;
    std::vector<std::string> messages_;
};

}  // namespace vkmesh::example
