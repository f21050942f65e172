// Fuzz target: calibration input. camera.json (nlohmann::json underneath, whose own exceptions must come
// out as vkmesh::Error), the --intrinsics "fx,fy,cx,cy" string and a 7-Scenes camera-intrinsics.txt (nine
// numbers). Values that pass must be usable: finite, non-zero positive focal lengths, positive depth scale.
#include "fuzz_common.h"
#include "io/dataset.h"
#include "io/parsers.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        std::istringstream in(text);
        vkmesh::io::CameraJson c = vkmesh::io::parseCameraJson(in, "camera.json");
        for (const auto& v : {c.fx, c.fy, c.cx, c.cy, c.depthScale})
            if (v && !std::isfinite(*v)) std::abort();
        if ((c.fx && *c.fx <= 0) || (c.fy && *c.fy == 0) || (c.depthScale && *c.depthScale <= 0)) std::abort();
        if ((c.width && *c.width <= 0) || (c.height && *c.height <= 0)) std::abort();
    });
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        vkmesh::Intrinsics k = vkmesh::parseIntrinsics(text);
        if (!(k.fx > 0) || k.fy == 0 || !std::isfinite(k.fy) || !std::isfinite(k.cx) || !std::isfinite(k.cy))
            std::abort();
    });
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        std::istringstream in(text);
        vkmesh::io::parseNumbers(in, "camera-intrinsics.txt", 9, "a 3x3 camera matrix");
    });
    return 0;
}
