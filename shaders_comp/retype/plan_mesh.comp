#version 460
// One invocation after mark_dirty: one invocation per retype-mask word of the dirty blocks (cache_neighbors,
// build_tsdf_masks, decide_mesh_signs, collect_retype); decide_mesh_signs' count of decided corners starts at 0;
// the retype list's dispatch (mesh_claim), which collect_retype raises as it lists (no one-invocation pass in
// between), and the changed-cube list start empty.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    counters.collectDispatch[0] = (counters.dirtyCount * MASK_WORDS + WG_LIST - 1u) / WG_LIST;
    counters.collectDispatch[1] = 1u;
    counters.collectDispatch[2] = 1u;
    counters.signCornerCount = 0u;
    counters.retypeDispatch[0] = 0u;
    counters.retypeDispatch[1] = 1u;
    counters.retypeDispatch[2] = 1u;
    counters.cubesChanged = 0u;
}
