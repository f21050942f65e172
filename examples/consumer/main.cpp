// Fuses a few frames of vkmesh's synthetic room on the GPU and exports the mesh, using only the installed
// package. Exits non-zero when the mesh is empty or the validation layer (VKMESH_VALIDATION=1) said anything.
#include <vkmesh.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
    using namespace vkmesh;
    try {
        vk::Context context;  // the first suitable device (lavapipe in CI); validation from VKMESH_VALIDATION=1
        std::printf("device: %s, validation %s\n", context.info().name.c_str(),
                    context.validationEnabled() ? "on" : "off");

        {  // the volume is destroyed before the messages are read, so its teardown is checked too
            constexpr int width = 160, height = 120;  // small frames: quick on a CPU driver
            const Intrinsics intrinsics = synth::kinectIntrinsics(width, height);
            const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();

            gpu::GpuVolumeConfig config;
            config.params.voxelSize = 0.04f;
            config.params.maxDepth = 6.0f;
            config.blockCapacity = 8192;
            config.imageWidth = width;
            config.imageHeight = height;
            gpu::GpuVolume volume(context, config);

            for (const Pose& pose : synth::cameraPath(6))
                volume.integrate(scene.renderDepth(intrinsics, pose), intrinsics, pose);

            const gpu::ExportedMesh exported = volume.exportMesh();
            std::printf("%zu triangles, %zu vertices after %u frames\n", exported.triangles.size(),
                        exported.vertices.size(), volume.framesIntegrated());
            if (exported.triangles.empty() || exported.vertices.empty()) {
                std::fprintf(stderr, "error: the mesh is empty\n");
                return 1;
            }
            if (argc > 1) {  // optional: write the mesh as PLY
                writePly(argv[1], toMesh(exported, volume.frameNumber()));
                std::printf("wrote %s\n", argv[1]);
            }
        }
        const auto messages = context.takeValidationMessages();
        for (const auto& m : messages) std::fprintf(stderr, "validation: %s\n", m.c_str());
        if (!messages.empty()) {
            std::fprintf(stderr, "error: %zu validation messages\n", messages.size());
            return 1;
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
