#version 460
// With refinement: the masks of the TSDF that decide_mesh_signs reads (raw sign, near, observed; shared_layout.h,
// MESH_SIGN_RAW...), computed from the TSDF for every mask word of the dirty blocks. Fusion and recycling keep
// them exact as they change the TSDF; this pass sets them where the TSDF came from elsewhere (a loaded map, whose
// masks are not saved). One invocation per mask word (32 corners).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/frame_lists.glsl"
#include "structure/block_store.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counters.dirtyCount * MASK_WORDS) return;
    uint block = dirtyList[i / MASK_WORDS], word = i % MASK_WORDS;
    uint raw = 0u, near = 0u, seen = 0u;
    for (uint b = 0u; b < 32u; ++b) {
        uint v = block * VOXELS_PER_BLOCK + word * 32u + b;
        uint bits = tsdfMaskBits(cornerSdf(v), voxelWeight[v]);
        raw |= (bits & 1u) << b;
        near |= ((bits >> 1) & 1u) << b;
        seen |= ((bits >> 2) & 1u) << b;
    }
    uint at = block * MESH_SIGN_WORDS + MESH_SIGN_GROUP * word;
    meshSigns[at + MESH_SIGN_RAW] = raw;
    meshSigns[at + MESH_SIGN_NEAR] = near;
    meshSigns[at + MESH_SIGN_OBSERVED] = seen;
}
