// Fuzz target: the .vkframes reader (FrameStore::load, src/core/frame_store.h). FrameStore::load reads a file, so
// each input is first written to a temporary file of this process. Bad input must be a vkmesh::Error; a store it
// accepts must give back every frame it holds (a depth image of width x height samples) and be one it can write,
// read again and write again to the same bytes.
#include "core/frame_store.h"
#include "fuzz_common.h"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

namespace {

// One set per process (libFuzzer's -fork/-jobs run several processes at once), overwritten by every input and
// removed at exit.
struct TempPaths {
    std::string input, again, third;
    TempPaths() {
        const std::string stem = "/tmp/vkmesh-fuzz-vkframes-" + std::to_string(::getpid());
        input = stem + "-input.vkframes", again = stem + "-again.vkframes", third = stem + "-third.vkframes";
    }
    ~TempPaths() {
        for (const std::string* p : {&input, &again, &third}) std::remove(p->c_str());
    }
};

const TempPaths& temp() {
    static const TempPaths paths;
    return paths;
}

void writeFile(const std::string& path, const uint8_t* data, size_t size) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    out.close();
    if (!out) {  // not a finding in the reader, but a run that tests nothing must not pass
        std::fprintf(stderr, "fuzz_vkframes: cannot write %s\n", path.c_str());
        std::abort();
    }
}

std::string readFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// What a store that load() accepted must allow; any exception here is a finding (load() decodes every frame
// before it accepts the file).
void checkAccepted(const vkmesh::FrameStore& store, uint64_t mapId, const vkmesh::FrameStoreOptions& options) {
    using namespace vkmesh;
    const std::vector<uint32_t> indices = store.indices();
    for (uint32_t index : indices) {
        const StoredFrame f = store.get(index);
        const size_t pixels = size_t(f.intrinsics.width) * size_t(f.intrinsics.height);
        if (f.index != index || f.depth.width != f.intrinsics.width || f.depth.height != f.intrinsics.height ||
            f.depth.meters.size() != pixels)
            std::abort();
        if (!f.color.empty() && (f.color.width != f.depth.width || f.color.height != f.depth.height || f.color.rgb.size() != 3 * pixels))
            std::abort();
    }
    const TempPaths& t = temp();
    store.save(t.again, mapId);
    const FrameStore reloaded = FrameStore::load(t.again, mapId, options);
    if (reloaded.indices() != indices) std::abort();
    reloaded.save(t.third, mapId);
    if (readFile(t.again) != readFile(t.third)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace vkmesh;
    const TempPaths& t = temp();
    writeFile(t.input, data, size);
    FrameStoreOptions options;
    options.memoryBudgetBytes = size_t(8) << 20;  // small, and no spill folder: a file past it must be an Error
    options.spillFolder.clear();
    uint64_t mapId = 0;
    std::optional<FrameStore> store;
    fuzz::expectOnlyVkmeshErrors([&] {
        mapId = FrameStore::mapIdOf(t.input);
        store.emplace(FrameStore::load(t.input, mapId, options));
    });
    if (!store) return 0;
    try {
        checkAccepted(*store, mapId, options);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fuzz_vkframes: a frame store that load() accepted fails: %s\n", e.what());
        std::abort();
    } catch (...) {
        std::fprintf(stderr, "fuzz_vkframes: a frame store that load() accepted fails (exception of unknown type)\n");
        std::abort();
    }
    return 0;
}
