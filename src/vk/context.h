// The Vulkan instance, the chosen physical device, a logical device with one compute queue, and the
// validation layer when asked for. Everything else in vkmesh (buffers, pipelines, command buffers)
// is created from a Context.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace vkmesh::vk {

struct ContextOptions {
    int deviceIndex = -1;     // index in `vkmesh devices`; -1: a discrete GPU if present, else any suitable one
    bool validation = false;  // Khronos validation layer; also on when VKMESH_VALIDATION=1 is set
};

struct DeviceInfo {
    uint32_t index = 0;
    std::string name;
    std::string type;         // "discrete GPU", "integrated GPU", "CPU", ...
    std::string apiVersion;   // "1.3.230"
    std::string driver;       // driver name and info where the device reports them
    bool suitable = false;
    std::string whyNot;       // what is missing when not suitable
    // The block hash's path (docs/HASH.md): 64-bit atomics when the device has shaderInt64 and
    // shaderBufferInt64Atomics (and VKMESH_PRETEND_MISSING names neither), else 32-bit atomics only.
    bool int64Atomics = false;
    std::string hashPath;     // "64-bit atomics" or "32-bit atomics (no ...)", for `vkmesh devices`
    // Unified memory: an integrated GPU or a CPU device (lavapipe) with a device-local memory type the host can
    // map coherently. The host then writes a frame's images where the shaders read them, with no staging
    // buffer and no copy (VKMESH_PRETEND_MISSING=unifiedMemory takes the staging path, as on a discrete GPU).
    bool unifiedMemory = false;
};

// The Vulkan feature names that VKMESH_PRETEND_MISSING (a comma list) may name: vkmesh then behaves as on
// a device without them, so CI tests the fallback paths on a device that has everything. Throws
// vkmesh::Error naming an unknown name and the known ones.
std::vector<std::string> pretendedMissingFeatures();

// An application's own Vulkan objects, for running vkmesh on them instead of creating its own
// (api/reconstructor.h). The application keeps owning them and destroys them after vkmesh. The device
// must have been created with the features in enableRequiredFeatures() and a queue of `queueFamily`
// that supports compute (and graphics, for vkmesh's renderer). vkmesh submits to that queue from the
// thread that calls it: the application must not submit to the same VkQueue concurrently.
struct ExternalDevice {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physicalDevice = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    uint32_t queueFamily = 0;
    uint32_t queueIndex = 0;
};

class Context {
public:
    explicit Context(const ContextOptions& options = {});
    // Runs on the application's device; creates only a command pool. Throws Error when the physical
    // device lacks what vkmesh needs or the queue family cannot compute.
    explicit Context(const ExternalDevice& external);
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    // Lists the physical devices and whether vkmesh can run on each.
    static std::vector<DeviceInfo> listDevices();
    // Sets the features vkmesh uses in an application's VkDeviceCreateInfo chain (features.pNext must
    // reach f12): timelineSemaphore (for Reconstructor::integrateAsync; core in Vulkan 1.2), and
    // shaderInt64 and shaderBufferInt64Atomics, which are optional (without them the block hash
    // takes its 32-bit path): this overload sets them unconditionally (device creation fails where they are
    // missing); the one taking the physical device sets only what the device has. Vulkan 1.2 required.
    static void enableRequiredFeatures(VkPhysicalDeviceFeatures2& features, VkPhysicalDeviceVulkan12Features& f12);
    static void enableRequiredFeatures(VkPhysicalDevice device, VkPhysicalDeviceFeatures2& features,
                                       VkPhysicalDeviceVulkan12Features& f12);
    // Whether the physical device can run vkmesh (DeviceInfo::whyNot says what is missing).
    static DeviceInfo describeDevice(VkPhysicalDevice device);
    // A compute queue family of the device, preferring one that also does graphics; throws if none.
    static uint32_t chooseQueueFamily(VkPhysicalDevice device);
    bool ownsDevice() const { return ownsDevice_; }

    VkInstance instance() const { return instance_; }
    VkPhysicalDevice physicalDevice() const { return physical_; }
    VkDevice device() const { return device_; }
    VkQueue queue() const { return queue_; }
    uint32_t queueFamily() const { return queueFamily_; }
    VkCommandPool commandPool() const { return commandPool_; }
    const VkPhysicalDeviceProperties& properties() const { return properties_; }
    const DeviceInfo& info() const { return info_; }
    bool validationEnabled() const { return validation_; }
    // Whether the block hash uses 64-bit atomics on this device (else its 32-bit path; docs/HASH.md).
    bool int64Atomics() const { return info_.int64Atomics; }
    // Whether per-frame inputs go straight into device-local, host-mapped memory (DeviceInfo::unifiedMemory).
    bool unifiedMemory() const { return info_.unifiedMemory; }

    // Memory type with all `required` flags (and `preferred` ones when possible); throws if none.
    uint32_t findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred = 0) const;

    // Timestamps: nanoseconds per tick, and whether the compute queue writes them at all.
    double timestampPeriodNs() const { return properties_.limits.timestampPeriod; }
    bool timestampsSupported() const { return timestampValidBits_ > 0; }
    uint32_t maxStorageBufferRange() const { return properties_.limits.maxStorageBufferRange; }

    // Validation-layer messages (warnings and errors) since the last call; tests fail on any.
    std::vector<std::string> takeValidationMessages();
    size_t validationMessageCount() const;

private:
    void release();  // destroys the Vulkan objects it owns (also on a failed construction)
    void initDeviceState(uint32_t queueIndex);   // queue, properties, command pool of the chosen device
    static VKAPI_ATTR VkBool32 VKAPI_CALL debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                        VkDebugUtilsMessageTypeFlagsEXT types,
                                                        const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                        void* user);

    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    uint32_t queueFamily_ = 0;
    VkCommandPool commandPool_ = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties properties_{};
    VkPhysicalDeviceMemoryProperties memoryProperties_{};
    uint32_t timestampValidBits_ = 0;
    DeviceInfo info_;
    bool validation_ = false;
    bool ownsDevice_ = true;

    mutable std::mutex messagesMutex_;
    std::vector<std::string> messages_;
    size_t messageCount_ = 0;
};

}  // namespace vkmesh::vk
