// Every compute pipeline binds only the buffers its shader uses (reflected from the SPIR-V), at most
// vk::kMaxStorageBuffersPerPipeline storage buffers, so GPU-assisted validation and small-limit devices fit.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include "shared_layout.h"
#include "vk/check.h"
#include "vk/pipeline.h"

using namespace vkmesh;

namespace {
bool uses(const std::vector<vk::ShaderBinding>& b, uint32_t binding) {
    return std::any_of(b.begin(), b.end(), [&](const vk::ShaderBinding& s) { return s.binding == binding; });
}
}  // namespace

TEST(PipelineLayouts, EveryShaderFitsTheStorageBufferBudget) {
    ASSERT_FALSE(shaders::all().empty());
    for (const auto& [name, spirv] : shaders::all()) {
        const auto bindings = vk::reflectBindings(spirv, name);
        const auto storage = std::count_if(bindings.begin(), bindings.end(),
                                           [](const vk::ShaderBinding& b) { return b.type == VK_DESCRIPTOR_TYPE_STORAGE_BUFFER; });
        std::cout << name << ": " << storage << " storage buffers\n";
        EXPECT_LE(storage, vk::kMaxStorageBuffersPerPipeline) << name;
        EXPECT_FALSE(bindings.empty()) << name << " reflects no binding at all";
    }
}

TEST(PipelineLayouts, ReflectionFindsWhatAShaderUsesAndNothingElse) {
    // commit_allocation moves the free list's top and decides a deferral: counters and params only, although its
    // headers declare more.
    const auto plan = vk::reflectBindings(shaders::all().at("commit_allocation"), "commit_allocation");
    ASSERT_EQ(plan.size(), 2u);
    EXPECT_EQ(plan[0].binding, gpu::BINDING_PARAMS);
    EXPECT_EQ(plan[0].type, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER);
    EXPECT_EQ(plan[1].binding, gpu::BINDING_COUNTERS);
    EXPECT_EQ(plan[1].type, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    // fuse_depth reads the depth image and writes the TSDF and the corners it flipped; it never touches the mesh
    // heaps, nor the cubes' retype masks (decide_mesh_signs marks the cubes around the flipped corners).
    const auto fuse = vk::reflectBindings(shaders::all().at("fuse_depth"), "fuse_depth");
    EXPECT_TRUE(uses(fuse, gpu::BINDING_DEPTH));
    EXPECT_TRUE(uses(fuse, gpu::BINDING_VOXEL_SDF));
    EXPECT_TRUE(uses(fuse, gpu::BINDING_CORNER_FLIPS));
    EXPECT_FALSE(uses(fuse, gpu::BINDING_RETYPE_MASK));
    EXPECT_FALSE(uses(fuse, gpu::BINDING_VERTICES));
    EXPECT_FALSE(uses(fuse, gpu::BINDING_CHUNK_TRIANGLES));
    // A buffer read through views of two types (fuse_depth's four-corner views of the voxel arrays,
    // decide_mesh_signs' groups of the mesh-sign words) is one descriptor, listed once.
    const auto decide = vk::reflectBindings(shaders::all().at("decide_mesh_signs"), "decide_mesh_signs");
    for (const auto* bindings : {&fuse, &decide})
        for (size_t i = 1; i < bindings->size(); ++i) EXPECT_NE((*bindings)[i].binding, (*bindings)[i - 1].binding);
    EXPECT_TRUE(uses(fuse, gpu::BINDING_VOXEL_WEIGHT));
    EXPECT_TRUE(uses(decide, gpu::BINDING_MESH_SIGNS));
}

TEST(PipelineLayouts, MalformedSpirvIsAClearError) {
    std::vector<uint32_t> junk = {0x12345678u, 0, 0, 0, 0};
    try {
        vk::reflectBindings(junk, "junk");
        FAIL() << "accepted a module without the SPIR-V magic number";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("junk"), std::string::npos);
    }
    std::vector<uint32_t> truncated(shaders::all().at("commit_allocation").begin(), shaders::all().at("commit_allocation").end());
    truncated.resize(40);
    EXPECT_THROW(vk::reflectBindings(truncated, "truncated"), Error);
}
