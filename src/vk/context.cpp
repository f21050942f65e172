#include "vk/context.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <optional>
#include <sstream>
#include <utility>

#include "vk/check.h"

namespace vkmesh::vk {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

bool envFlag(const char* name) {
    const char* v = std::getenv(name);
    return v && *v && std::strcmp(v, "0") != 0;
}

std::string versionString(uint32_t v) {
    return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
           std::to_string(VK_API_VERSION_PATCH(v));
}

std::string typeName(VkPhysicalDeviceType t) {
    switch (t) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
        default: return "other";
    }
}

int typeRank(VkPhysicalDeviceType t) {
    switch (t) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
        default: return 4;
    }
}

bool layerAvailable(const char* name) {
    uint32_t n = 0;
    vkEnumerateInstanceLayerProperties(&n, nullptr);
    std::vector<VkLayerProperties> layers(n);
    vkEnumerateInstanceLayerProperties(&n, layers.data());
    return std::any_of(layers.begin(), layers.end(), [&](const auto& l) { return std::strcmp(l.layerName, name) == 0; });
}

VkInstance createInstance(bool validation) {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "vkmesh";
    app.pEngineName = "vkmesh";
    app.apiVersion = VK_API_VERSION_1_2;
    std::vector<const char*> layers, extensions;
    // With validation, synchronization validation too: a missing barrier between two stages is a bug
    // that lavapipe (which runs dispatches in order) would never show.
    VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
    VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
    features.enabledValidationFeatureCount = 1;
    features.pEnabledValidationFeatures = enables;
    if (validation) {
        layers.push_back(kValidationLayer);
        extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
        extensions.push_back(VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
    }
    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    if (validation) info.pNext = &features;
    info.pApplicationInfo = &app;
    info.enabledLayerCount = static_cast<uint32_t>(layers.size());
    info.ppEnabledLayerNames = layers.data();
    info.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
    info.ppEnabledExtensionNames = extensions.data();
    VkInstance instance = VK_NULL_HANDLE;
    VkResult r = vkCreateInstance(&info, nullptr, &instance);
    if (r == VK_ERROR_INCOMPATIBLE_DRIVER || r == VK_ERROR_INITIALIZATION_FAILED)
        throw Error(std::string("No Vulkan driver could be loaded (vkCreateInstance: ") + resultName(r) +
                    "). Install a Vulkan driver: `apt-get install mesa-vulkan-drivers` gives the lavapipe CPU "
                    "device; GPU vendors ship their own.");
    check(r, "vkCreateInstance");
    return instance;
}

std::vector<VkPhysicalDevice> physicalDevices(VkInstance instance) {
    uint32_t n = 0;
    check(vkEnumeratePhysicalDevices(instance, &n, nullptr), "vkEnumeratePhysicalDevices");
    std::vector<VkPhysicalDevice> devices(n);
    check(vkEnumeratePhysicalDevices(instance, &n, devices.data()), "vkEnumeratePhysicalDevices");
    return devices;
}

std::optional<uint32_t> computeQueueFamily(VkPhysicalDevice device) {
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(device, &n, nullptr);
    std::vector<VkQueueFamilyProperties> families(n);
    vkGetPhysicalDeviceQueueFamilyProperties(device, &n, families.data());
    // Prefer a family that also does graphics (the renderer shares it later), else any compute family.
    for (uint32_t i = 0; i < n; ++i)
        if ((families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) && (families[i].queueFlags & VK_QUEUE_GRAPHICS_BIT)) return i;
    for (uint32_t i = 0; i < n; ++i)
        if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) return i;
    return std::nullopt;
}

constexpr const char* kPretendableFeatures[] = {"shaderInt64", "shaderBufferInt64Atomics", "unifiedMemory"};

bool pretendMissing(const std::vector<std::string>& missing, const char* feature) {
    return std::find(missing.begin(), missing.end(), feature) != missing.end();
}

// What vkmesh needs from a device (README, "Requirements"): Vulkan 1.2, a compute queue, basic/arithmetic/
// ballot subgroup operations in compute shaders (counters are aggregated per subgroup) and the limits below.
// 64-bit integers and 64-bit buffer atomics are optional: with both, a hash key is claimed with one 64-bit
// compare-and-swap; without, the hash takes its 32-bit path (docs/HASH.md).
DeviceInfo describe(VkPhysicalDevice device, uint32_t index) {
    const std::vector<std::string> pretended = pretendedMissingFeatures();
    VkPhysicalDeviceProperties props{};
    vkGetPhysicalDeviceProperties(device, &props);
    VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
    VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
    subgroup.pNext = props.apiVersion >= VK_API_VERSION_1_2 ? &driver : nullptr;
    VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    props2.pNext = &subgroup;
    vkGetPhysicalDeviceProperties2(device, &props2);

    DeviceInfo info;
    info.index = index;
    info.name = props.deviceName;
    info.type = typeName(props.deviceType);
    info.apiVersion = versionString(props.apiVersion);
    if (props.apiVersion >= VK_API_VERSION_1_2) info.driver = std::string(driver.driverName) + " " + driver.driverInfo;

    std::vector<std::string> missing;
    if (props.apiVersion < VK_API_VERSION_1_2) missing.push_back("Vulkan 1.2");
    if (!computeQueueFamily(device)) missing.push_back("a compute queue");
    if (props.apiVersion >= VK_API_VERSION_1_2) {
        VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
        VkPhysicalDeviceFeatures2 f{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
        f.pNext = &f12;
        vkGetPhysicalDeviceFeatures2(device, &f);
        std::vector<std::string> no64;
        if (!f.features.shaderInt64 || pretendMissing(pretended, "shaderInt64")) no64.push_back("shaderInt64");
        if (!f12.shaderBufferInt64Atomics || pretendMissing(pretended, "shaderBufferInt64Atomics"))
            no64.push_back("shaderBufferInt64Atomics");
        info.int64Atomics = no64.empty();
        info.hashPath = "64-bit atomics";
        if (!no64.empty()) {
            info.hashPath = "32-bit atomics (no ";
            for (size_t i = 0; i < no64.size(); ++i) info.hashPath += (i ? ", " : "") + no64[i];
            info.hashPath += ")";
        }
        VkSubgroupFeatureFlags need = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_ARITHMETIC_BIT | VK_SUBGROUP_FEATURE_BALLOT_BIT;
        if ((subgroup.supportedOperations & need) != need || !(subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT))
            missing.push_back("subgroup basic+arithmetic+ballot operations in compute shaders");
        // Limits above Vulkan's guaranteed minimums that the compute pipelines rely on: up to
        // kMaxStorageBuffersPerPipeline (vk/pipeline.h) storage buffers per pipeline, 16 x 16 pixel workgroups.
        const VkPhysicalDeviceLimits& l = props.limits;
        auto atLeast = [&](uint64_t have, uint64_t need, const char* limit) {
            if (have < need) missing.push_back(std::string(limit) + " >= " + std::to_string(need) + " (has " + std::to_string(have) + ")");
        };
        atLeast(l.maxPerStageDescriptorStorageBuffers, 16, "maxPerStageDescriptorStorageBuffers");
        atLeast(l.maxComputeWorkGroupInvocations, 256, "maxComputeWorkGroupInvocations");
    }
    // A discrete GPU may also offer a device-local type the host can map (a PCIe BAR); the host's writes would
    // then cross the bus uncached, so only a device sharing the host's memory writes its inputs in place.
    if ((props.deviceType == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU || props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU) &&
        !pretendMissing(pretended, "unifiedMemory")) {
        VkPhysicalDeviceMemoryProperties memory{};
        vkGetPhysicalDeviceMemoryProperties(device, &memory);
        const VkMemoryPropertyFlags mapped = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                             VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        for (uint32_t i = 0; i < memory.memoryTypeCount; ++i)
            if ((memory.memoryTypes[i].propertyFlags & mapped) == mapped) info.unifiedMemory = true;
    }
    info.suitable = missing.empty();
    for (size_t i = 0; i < missing.size(); ++i) info.whyNot += (i ? ", " : "missing ") + missing[i];
    return info;
}

}  // namespace

std::vector<std::string> pretendedMissingFeatures() {
    const char* env = std::getenv("VKMESH_PRETEND_MISSING");
    std::vector<std::string> out;
    if (!env) return out;
    std::stringstream list(env);
    std::string name;
    while (std::getline(list, name, ',')) {
        name.erase(0, name.find_first_not_of(" \t"));
        name.erase(name.find_last_not_of(" \t") + 1);
        if (name.empty()) continue;
        if (std::find(std::begin(kPretendableFeatures), std::end(kPretendableFeatures), name) == std::end(kPretendableFeatures)) {
            std::string known;
            for (const char* k : kPretendableFeatures) known += std::string(known.empty() ? "" : ", ") + k;
            throw Error("VKMESH_PRETEND_MISSING names '" + name + "', which is not a Vulkan feature vkmesh can do without; known: " + known);
        }
        out.push_back(name);
    }
    return out;
}

std::vector<DeviceInfo> Context::listDevices() {
    VkInstance instance = createInstance(false);
    std::vector<DeviceInfo> out;
    try {
        auto devices = physicalDevices(instance);
        for (uint32_t i = 0; i < devices.size(); ++i) out.push_back(describe(devices[i], i));
    } catch (...) {
        vkDestroyInstance(instance, nullptr);
        throw;
    }
    vkDestroyInstance(instance, nullptr);
    return out;
}

Context::Context(const ContextOptions& options) {
    validation_ = options.validation || envFlag("VKMESH_VALIDATION");
    if (validation_ && !layerAvailable(kValidationLayer))
        throw Error("Validation was requested but VK_LAYER_KHRONOS_validation is not installed "
                    "(apt-get install vulkan-validationlayers)");
    instance_ = createInstance(validation_);
    try {
        if (validation_) {
            VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
            info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
            info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
            info.pfnUserCallback = &Context::debugCallback;
            info.pUserData = this;
            auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
            if (!create) throw Error("vkCreateDebugUtilsMessengerEXT is not available with the validation layer");
            check(create(instance_, &info, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
        }

        auto devices = physicalDevices(instance_);
        if (devices.empty())
            throw Error("No Vulkan device found. Install a driver: `apt-get install mesa-vulkan-drivers` "
                        "gives the lavapipe CPU device; GPU vendors ship their own.");
        std::vector<DeviceInfo> infos;
        for (uint32_t i = 0; i < devices.size(); ++i) infos.push_back(describe(devices[i], i));

        int chosen = -1;
        if (options.deviceIndex >= 0) {
            if (options.deviceIndex >= static_cast<int>(devices.size()))
                throw Error("--device " + std::to_string(options.deviceIndex) + " does not exist: there are " +
                            std::to_string(devices.size()) + " Vulkan devices (see `vkmesh devices`)");
            if (!infos[options.deviceIndex].suitable)
                throw Error("Device " + std::to_string(options.deviceIndex) + " (" + infos[options.deviceIndex].name +
                            ") cannot run vkmesh: " + infos[options.deviceIndex].whyNot);
            chosen = options.deviceIndex;
        } else {
            int bestRank = 1 << 30;
            for (uint32_t i = 0; i < devices.size(); ++i) {
                if (!infos[i].suitable) continue;
                VkPhysicalDeviceProperties p{};
                vkGetPhysicalDeviceProperties(devices[i], &p);
                if (typeRank(p.deviceType) < bestRank) bestRank = typeRank(p.deviceType), chosen = static_cast<int>(i);
            }
            if (chosen < 0) {
                std::string why;
                for (const auto& d : infos) why += "\n  " + std::to_string(d.index) + ": " + d.name + ": " + d.whyNot;
                throw Error("No Vulkan device can run vkmesh:" + why);
            }
        }
        physical_ = devices[chosen];
        info_ = infos[chosen];
        queueFamily_ = *computeQueueFamily(physical_);

        float priority = 1.0f;
        VkDeviceQueueCreateInfo queueInfo{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        queueInfo.queueFamilyIndex = queueFamily_;
        queueInfo.queueCount = 1;
        queueInfo.pQueuePriorities = &priority;
        VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
        VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
        features.pNext = &f12;
        enableRequiredFeatures(physical_, features, f12);
        VkDeviceCreateInfo deviceInfo{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        deviceInfo.pNext = &features;
        deviceInfo.queueCreateInfoCount = 1;
        deviceInfo.pQueueCreateInfos = &queueInfo;
        check(vkCreateDevice(physical_, &deviceInfo, nullptr, &device_), "vkCreateDevice");
        initDeviceState(0);
    } catch (...) {
        release();
        throw;
    }
}

Context::Context(const ExternalDevice& external) {
    ownsDevice_ = false;
    if (!external.instance || !external.physicalDevice || !external.device)
        throw Error("ExternalDevice: instance, physicalDevice and device must all be set");
    instance_ = external.instance;
    physical_ = external.physicalDevice;
    device_ = external.device;
    try {
        info_ = describe(physical_, 0);
        if (!info_.suitable)
            throw Error("The application's device (" + info_.name + ") cannot run vkmesh: " + info_.whyNot);
        uint32_t n = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(physical_, &n, nullptr);
        std::vector<VkQueueFamilyProperties> families(n);
        vkGetPhysicalDeviceQueueFamilyProperties(physical_, &n, families.data());
        if (external.queueFamily >= n || !(families[external.queueFamily].queueFlags & VK_QUEUE_COMPUTE_BIT))
            throw Error("ExternalDevice: queue family " + std::to_string(external.queueFamily) + " of " + info_.name +
                        " does not exist or cannot run compute shaders");
        if (external.queueIndex >= families[external.queueFamily].queueCount)
            throw Error("ExternalDevice: queue family " + std::to_string(external.queueFamily) + " has " +
                        std::to_string(families[external.queueFamily].queueCount) + " queues, no index " +
                        std::to_string(external.queueIndex));
        queueFamily_ = external.queueFamily;
        initDeviceState(external.queueIndex);
    } catch (...) {
        release();
        throw;
    }
}

void Context::initDeviceState(uint32_t queueIndex) {
    vkGetPhysicalDeviceProperties(physical_, &properties_);
    vkGetPhysicalDeviceMemoryProperties(physical_, &memoryProperties_);
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &n, nullptr);
    std::vector<VkQueueFamilyProperties> families(n);
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &n, families.data());
    timestampValidBits_ = families[queueFamily_].timestampValidBits;
    vkGetDeviceQueue(device_, queueFamily_, queueIndex, &queue_);
    VkCommandPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    poolInfo.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    poolInfo.queueFamilyIndex = queueFamily_;
    check(vkCreateCommandPool(device_, &poolInfo, nullptr, &commandPool_), "vkCreateCommandPool");
}

void Context::enableRequiredFeatures(VkPhysicalDeviceFeatures2& features, VkPhysicalDeviceVulkan12Features& f12) {
    features.features.shaderInt64 = VK_TRUE;
    f12.shaderBufferInt64Atomics = VK_TRUE;
    f12.timelineSemaphore = VK_TRUE;
}

void Context::enableRequiredFeatures(VkPhysicalDevice device, VkPhysicalDeviceFeatures2& features,
                                     VkPhysicalDeviceVulkan12Features& f12) {
    // Only for the 64-bit hash path; a device on the 32-bit path (or pretending to be) gets neither, so the
    // validation layer reports any shader that would still use a 64-bit type.
    if (describe(device, 0).int64Atomics) enableRequiredFeatures(features, f12);
    // Reconstructor::integrateAsync signals a timeline semaphore; every Vulkan 1.2 device supports them.
    f12.timelineSemaphore = VK_TRUE;
}

DeviceInfo Context::describeDevice(VkPhysicalDevice device) { return describe(device, 0); }

uint32_t Context::chooseQueueFamily(VkPhysicalDevice device) {
    auto family = computeQueueFamily(device);
    if (!family) throw Error("the device has no compute queue family");
    return *family;
}

Context::~Context() { release(); }

void Context::release() {
    if (!ownsDevice_) {
        // The application's objects: wait for vkmesh's own work only, destroy only what vkmesh created.
        if (device_ && queue_) vkQueueWaitIdle(queue_);
        if (device_ && commandPool_) vkDestroyCommandPool(device_, commandPool_, nullptr);
        commandPool_ = VK_NULL_HANDLE;
        device_ = VK_NULL_HANDLE;
        instance_ = VK_NULL_HANDLE;
        return;
    }
    if (device_) {
        vkDeviceWaitIdle(device_);
        if (commandPool_) vkDestroyCommandPool(device_, commandPool_, nullptr);
        vkDestroyDevice(device_, nullptr);
    }
    if (messenger_) {
        auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
        if (destroy) destroy(instance_, messenger_, nullptr);
    }
    if (instance_) vkDestroyInstance(instance_, nullptr);
    commandPool_ = VK_NULL_HANDLE;
    device_ = VK_NULL_HANDLE;
    messenger_ = VK_NULL_HANDLE;
    instance_ = VK_NULL_HANDLE;
}

uint32_t Context::findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const {
    for (int pass = 0; pass < 2; ++pass) {
        VkMemoryPropertyFlags want = pass == 0 ? (required | preferred) : required;
        for (uint32_t i = 0; i < memoryProperties_.memoryTypeCount; ++i)
            if ((typeBits & (1u << i)) && (memoryProperties_.memoryTypes[i].propertyFlags & want) == want) return i;
    }
    throw Error("No Vulkan memory type with property flags " + std::to_string(required) + " on " + info_.name);
}

VKAPI_ATTR VkBool32 VKAPI_CALL Context::debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                      VkDebugUtilsMessageTypeFlagsEXT,
                                                      const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    auto* self = static_cast<Context*>(user);
    std::string text = std::string(severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT ? "[validation error] " : "[validation warning] ") +
                       (data && data->pMessage ? data->pMessage : "");
    std::cerr << text << "\n";
    std::lock_guard<std::mutex> lock(self->messagesMutex_);
    self->messages_.push_back(std::move(text));
    ++self->messageCount_;
    return VK_FALSE;
}

std::vector<std::string> Context::takeValidationMessages() {
    std::lock_guard<std::mutex> lock(messagesMutex_);
    return std::exchange(messages_, {});
}

size_t Context::validationMessageCount() const {
    std::lock_guard<std::mutex> lock(messagesMutex_);
    return messageCount_;
}

}  // namespace vkmesh::vk
