// `vkmesh devices`: the Vulkan devices and whether vkmesh can use them (exit code 1 when there is none).
#include <CLI/CLI.hpp>

#include <iostream>

#include "commands.h"
#include "vk/context.h"

namespace vkmesh::cli {

Run addDevicesCommand(CLI::App& app) {
    app.add_subcommand("devices", "list Vulkan devices and whether vkmesh can use them");
    return [] {
        auto devices = vk::Context::listDevices();
        if (devices.empty()) {
            std::cout << "No Vulkan device. Install a driver (apt-get install mesa-vulkan-drivers gives lavapipe).\n";
            return 1;
        }
        for (const auto& d : devices) {
            std::cout << d.index << ": " << d.name << " (" << d.type << ", Vulkan " << d.apiVersion << ", " << d.driver << ")"
                      << (d.suitable ? "; block hash: " + d.hashPath + (d.unifiedMemory ? "; unified memory" : "") : "  NOT USABLE: " + d.whyNot) << "\n";
        }
        return 0;
    };
}

}  // namespace vkmesh::cli
