#include "slam/session_join.h"

#include <chrono>
#include <functional>
#include <optional>
#include <system_error>

#include "api/mapper.h"
#include "core/map_format.h"
#include "core/map_merge.h"
#include "gpu/gpu_volume.h"
#include "gpu/map_corrector.h"
#include "vk/context.h"

namespace vkmesh::slam {

namespace {

struct Session {
    std::filesystem::path path;
    map::MapData map;
    FrameStore frames;
};

Session readSession(const std::filesystem::path& path, const FrameStoreOptions& options) {
    Session s{path, map::readFile(path), FrameStore(options)};
    const std::filesystem::path store = gpu::frameStorePathOf(path);
    if (!std::filesystem::exists(store))
        throw Error(path.string() + " has no frame store beside it (" + store.string() +
                    "): joining sessions registers and re-fuses their frames; save the map with vkmesh fuse ... --save (which keeps them)");
    s.frames = FrameStore::load(store.string(), s.map.saveId, options);
    return s;
}

// The temporary maps of the moved sessions, removed however the join ends.
struct Temporaries {
    std::vector<std::filesystem::path> paths;
    ~Temporaries() {
        std::error_code ignored;
        for (const auto& p : paths) std::filesystem::remove(p, ignored), std::filesystem::remove(gpu::frameStorePathOf(p), ignored);
    }
};

// The join, on the device `device` gives once the inputs are read and checked.
JoinReport joinWith(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output, const JoinOptions& options,
                    const std::function<const vk::Context&()>& device);

}  // namespace

JoinReport joinSessions(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output, const JoinOptions& options) {
    // Every input is read and checked before a device is opened.
    std::optional<vk::Context> context;
    return joinWith(inputs, output, options, [&]() -> const vk::Context& { return context.emplace(options.merge.device); });
}

JoinReport joinSessions(const vk::Context& context, const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output,
                        const JoinOptions& options) {
    return joinWith(inputs, output, options, [&]() -> const vk::Context& { return context; });
}

namespace {

JoinReport joinWith(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output, const JoinOptions& options,
                    const std::function<const vk::Context&()>& device) {
    if (inputs.size() < 2) throw Error("joining sessions needs two maps or more (the first gives the world frame)");
    if (output.empty()) throw Error("joining sessions: give the joined map's path");
    JoinReport report;
    const Session first = readSession(inputs.front(), options.merge.frames);
    std::vector<Session> later;
    for (size_t i = 1; i < inputs.size(); ++i) {
        later.push_back(readSession(inputs[i], options.merge.frames));
        // Settings are compared before any work (merging would refuse them only after the registration).
        const auto differences = map::settingDifferences(first.map.settings, later.back().map.settings, map::AllocationRules::Exact);
        if (!differences.empty()) {
            const map::SettingDifference& d = differences.front();
            throw Error(inputs[i].string() + " cannot join " + inputs.front().string() + ": its " + d.what + " (" + d.option + ") is " +
                        std::to_string(d.b) + ", the first map's " + std::to_string(d.a));
        }
    }
    for (size_t i = 0; i < later.size(); ++i) {
        try {
            report.registrations.push_back(registerSessions(first.frames, later[i].frames, options.registration));
        } catch (const Error& e) {
            throw Error(later[i].path.string() + " to " + first.path.string() + ": " + e.what());
        }
    }

    // Each later session's frames fused afresh at their poses in the first's frame (the map one run at those poses
    // makes, with the frames' indices and timestamps; exact, as a correction would be at twice the cost), then saved
    // beside the output to be added.
    const auto start = std::chrono::steady_clock::now();
    const vk::Context& context = device();
    Temporaries moved;
    for (size_t i = 0; i < later.size(); ++i) {
        Session& s = later[i];
        MapperOptions mapperOptions;
        mapperOptions.volume = gpu::GpuVolume::mapConfig(s.map);
        if (mapperOptions.volume.meshMode != gpu::MeshMode::Incremental)
            throw Error(s.path.string() + " was fused with --mode baseline; joining needs maps fused with --mode incremental");
        mapperOptions.volume.imageWidth = mapperOptions.volume.imageHeight = 0;   // from the frames
        Mapper mapper(context, mapperOptions);
        mapper.keepFrames(FrameStore(options.merge.frames));
        const Pose& secondToFirst = report.registrations[i].secondToFirst;
        for (uint32_t index : s.frames.indices()) {
            const StoredFrame f = s.frames.get(index);
            MapperFrame frame;
            frame.index = f.index;
            frame.timestamp = f.timestamp;
            frame.depth = &f.depth;
            frame.color = f.color.empty() ? nullptr : &f.color;
            frame.intrinsics = f.intrinsics;
            frame.pose = secondToFirst * f.pose;
            frame.source = s.path.string() + ", frame " + std::to_string(f.index);
            const MapperResult r = mapper.process(frame);
            if (r.status != FrameStatus::Fused)
                throw Error(frame.source + " could not be fused in " + first.path.string() + "'s frame" +
                            (r.warnings.empty() ? std::string() : ": " + r.warnings.front()));
            ++report.framesMoved;
        }
        mapper.finish();
        const std::filesystem::path temporary = output.string() + ".session" + std::to_string(i + 2) + ".vkmap";
        moved.paths.push_back(temporary);
        mapper.save(temporary);
    }
    report.moveMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

    std::vector<std::filesystem::path> sum{first.path};
    sum.insert(sum.end(), moved.paths.begin(), moved.paths.end());
    report.merge = mergeMaps(context, sum, output, options.merge);
    for (size_t i = 1; i < report.merge.inputs.size(); ++i) report.merge.inputs[i].path = inputs[i].string();
    return report;
}

}  // namespace

}  // namespace vkmesh::slam
