// Every setting of a run, described once: its name on the command line and in Python, its default (taken from the
// library's own defaults), its range or choices, its kind and its help. The CLI registers its options from these
// descriptions (host/cli_options.h, addSetting), a map's settings are taken on --load by them (Map kind), and tests
// check Python's keywords and defaults (tests/python/test_settings.py) and the docs against them, so that the
// front ends and the docs cannot drift apart.
#pragma once

#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "gpu/gpu_volume.h"

namespace vkmesh {

enum class SettingKind {
    Map,              // decides what the map holds: saved with it, taken from it on --load (a value given must agree)
    Capacity,         // an initial size, grown when full; on --load the larger of the map's and the given one
    Processing,       // how the work is done; the map is the same either way (lock-free claims, ...)
    Tracking,         // the camera tracker's
    Correction,       // kept frames, their corrections, loop closure
    Instrumentation,  // what is timed or analysed for the statistics; the map is the same either way
    Input,            // how the input is read
    Output,           // what is written, served or shown
    Device,           // which Vulkan device, with what checks
};
const char* toString(SettingKind kind);

struct SettingDescription {
    std::string cli;       // the command line's name ("--voxel"); empty when only Python has it
    std::string python;    // Python's keyword ("voxel_size"); empty when only the command line has it
    SettingKind kind;
    std::string defaultValue;   // the library's default as text ("0.03", "true", "16384", "average"); "" for none
    double min = -std::numeric_limits<double>::infinity();   // a number's range, inclusive (min exclusive with
    double max = std::numeric_limits<double>::infinity();    // minExclusive); both infinite: any number
    bool minExclusive = false;
    std::vector<std::string> choices;   // a text setting's values
    std::string help;
    // The command-line flag says the opposite of Python's keyword (--no-grow against grow_capacities=True).
    bool cliNegates = false;
    std::string deprecated;   // why it has no effect any more (a message is printed when it is given); "" when it has one
    // Map settings taken from a map on --load when the command line did not give them (also not as `givenWith`).
    void (*fromMap)(const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& config) = nullptr;
    std::string givenWith;    // another option that sets the same thing (--alloc-pixels for --alloc-tiles)
};

// Every setting, in the order the CLI's help lists them.
const std::vector<SettingDescription>& settingDescriptions();
// The setting of that command-line name ("--voxel") or Python keyword ("voxel_size"); throws Error when none has it.
const SettingDescription& setting(std::string_view name);

// The depth beyond which both front ends ignore measurements by default (metres).
inline constexpr float kDefaultMaxDepth = 4.0f;

// A float as the shortest decimal that reads back as the same float ("0.03"): how defaults are written.
std::string shortestText(float value);

}  // namespace vkmesh
