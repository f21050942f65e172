#version 460
// One invocation per block of the pool: a live block (its hash slot holds it) whose bounding sphere can reach the
// view is listed, and list_view_chunks gets a workgroup for it. Conservative: a block left out lies wholly outside
// one of the view's six planes, so none of its triangles covers a pixel centre of the maps; the maps drawn from the
// list are the maps of the whole mesh. The pool is a fixed cost per frame (~16k invocations by default) that does
// not grow with the map; everything after it follows the blocks in view.
#extension GL_GOOGLE_include_directive : require
#include "model_view.glsl"

layout(local_size_x = WG_LIST) in;

// Signed distance of the camera-space point (along, z) to the plane through the optical centre with normal
// (a, b) in that coordinate plane, positive inside.
float planeDistance(float along, float z, float a, float b) { return (a * along + b * z) * inversesqrt(a * a + b * b); }

bool sphereInView(vec3 c, float r) {
    float width = pc.viewport.x, height = pc.viewport.y, near = pc.viewport.z, far = pc.viewport.w;
    if (c.z + r < near || c.z - r > far) return false;
    // u = fx x / z + cx >= lo  <=>  fx x + (cx - lo) z >= 0 for z > 0; u <= hi  <=>  -fx x + (hi - cx) z >= 0 (either
    // sign of fx). A pixel's width of margin beyond the framebuffer's [-0.5, size - 0.5], against rounding.
    float fx = pc.intrinsics.x, fy = pc.intrinsics.y, cx = pc.intrinsics.z, cy = pc.intrinsics.w;
    float lo = -1.5, hiX = width + 0.5, hiY = height + 0.5;
    return planeDistance(c.x, c.z, fx, cx - lo) >= -r && planeDistance(c.x, c.z, -fx, hiX - cx) >= -r &&
           planeDistance(c.y, c.z, fy, cy - lo) >= -r && planeDistance(c.y, c.z, -fy, hiY - cy) >= -r;
}

void main() {
    uint block = gl_GlobalInvocationID.x;
    bool listed = false;
    if (block < pc.blockCapacity) {
        ivec4 coord = blockCoords[block];
        vec3 w = (vec3(coord.xyz) + 0.5) * pc.blockSide;   // the block's centre
        vec3 c = vec3(dot(pc.worldToCamera[0].xyz, w) + pc.worldToCamera[0].w, dot(pc.worldToCamera[1].xyz, w) + pc.worldToCamera[1].w,
                      dot(pc.worldToCamera[2].xyz, w) + pc.worldToCamera[2].w);
        // A free block's coordinate is stale (or was never written): its hash slot no longer names it.
        listed = sphereInView(c, pc.blockRadius) && coord.w >= 0 && uint(coord.w) < pc.hashCapacity && hashValues[uint(coord.w)] == block;
    }
    uint at;
    APPEND_PER_SUBGROUP(viewState.blockDispatch[0], listed ? 1u : 0u, at);
    if (listed) viewBlocks[at] = block;
}
