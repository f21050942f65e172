// Declarations shared by every vkmesh compute stage: the data structure's buffers (one descriptor set
// for all stages, binding numbers from shared_layout.h), the frame's push constants, and the hash and
// grid helpers. Rules that hold in every stage (see ../shared/docs/lavapipe.md):
//   - no invocation waits for another; every loop has a static bound far below 65,535 iterations;
//   - what one invocation publishes with an atomic, others read in the NEXT dispatch;
//   - float expressions that the CPU reference must reproduce bit for bit are `precise`.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require

#include "shared_layout.h"

layout(std140, set = 0, binding = BINDING_PARAMS) uniform ParamsBuffer { VolumeParamsGpu params; };
layout(std430, set = 0, binding = BINDING_COUNTERS) coherent buffer CountersBuffer { Counters counters; };
layout(std430, set = 0, binding = BINDING_HASH_KEYS) coherent buffer HashKeys { uint64_t hashKeys[]; };
layout(std430, set = 0, binding = BINDING_HASH_VALUES) coherent buffer HashValues { uint hashValues[]; };
layout(std430, set = 0, binding = BINDING_HASH_STAMPS) coherent buffer HashStamps { uint hashStamps[]; };
layout(std430, set = 0, binding = BINDING_BLOCK_COORDS) buffer BlockCoords { ivec4 blockCoords[]; };
layout(std430, set = 0, binding = BINDING_VOXEL_SDF) buffer VoxelSdf { float voxelSdf[]; };
layout(std430, set = 0, binding = BINDING_VOXEL_WEIGHT) buffer VoxelWeight { float voxelWeight[]; };
layout(std430, set = 0, binding = BINDING_FREE_LIST) buffer FreeList { uint freeList[]; };
layout(std430, set = 0, binding = BINDING_TOUCHED) buffer Touched { uint touched[]; };
layout(std430, set = 0, binding = BINDING_DEPTH) readonly buffer Depth { float depth[]; };
layout(std430, set = 0, binding = BINDING_MC_TABLES) readonly buffer McTables { uint mcTables[]; };
layout(std430, set = 0, binding = BINDING_BLOCK_LIST) buffer BlockList { uint blockList[]; };
layout(std430, set = 0, binding = BINDING_MESH_VERTICES) buffer MeshVertices { vec4 meshVertices[]; };
layout(std430, set = 0, binding = BINDING_CUBE_STATE) buffer CubeState { uint cubeState[]; };
layout(std430, set = 0, binding = BINDING_EDGE_VERTEX_X) coherent buffer EdgeVertexX { uint edgeVertexX[]; };
layout(std430, set = 0, binding = BINDING_EDGE_VERTEX_Y) coherent buffer EdgeVertexY { uint edgeVertexY[]; };
layout(std430, set = 0, binding = BINDING_EDGE_VERTEX_Z) coherent buffer EdgeVertexZ { uint edgeVertexZ[]; };
layout(std430, set = 0, binding = BINDING_MESH_STAMPS) coherent buffer MeshStamps { uint meshStamps[]; };
layout(std430, set = 0, binding = BINDING_DIRTY_LIST) buffer DirtyList { uint dirtyList[]; };
layout(std430, set = 0, binding = BINDING_VERTICES) coherent buffer Vertices { Vertex vertices[]; };
layout(std430, set = 0, binding = BINDING_VERTEX_OWNER) buffer VertexOwner { uint vertexOwner[]; };
layout(std430, set = 0, binding = BINDING_VERTEX_FREE) buffer VertexFree { uint vertexFree[]; };
layout(std430, set = 0, binding = BINDING_GC_CANDIDATES) buffer GcCandidates { uint gcCandidates[]; };
layout(std430, set = 0, binding = BINDING_CHUNK_TRIANGLES) buffer ChunkTriangles { uint chunkTriangles[]; };
layout(std430, set = 0, binding = BINDING_CHUNK_FREE) buffer ChunkFree { uint chunkFree[]; };
layout(std430, set = 0, binding = BINDING_CHUNK_RELEASE) buffer ChunkRelease { uint chunkRelease[]; };
layout(std430, set = 0, binding = BINDING_EXPORT_VERTICES) buffer ExportVertices { Vertex exportVertices[]; };
layout(std430, set = 0, binding = BINDING_EXPORT_INDICES) buffer ExportIndices { uint exportIndices[]; };
layout(std430, set = 0, binding = BINDING_VERTEX_REMAP) buffer VertexRemap { uint vertexRemap[]; };
layout(std430, set = 0, binding = BINDING_RETYPE_MASK) coherent buffer RetypeMask { uint retypeMask[]; };
layout(std430, set = 0, binding = BINDING_RETYPE_LIST) buffer RetypeList { uint retypeList[]; };

layout(push_constant) uniform Push { FramePush frame; };

// ---- block keys ------------------------------------------------------------------------------------
bool blockCoordInRange(ivec3 c) {
    return all(greaterThanEqual(c, ivec3(-int(KEY_BIAS)))) && all(lessThan(c, ivec3(int(KEY_BIAS))));
}

uint64_t packBlockKey(ivec3 c) {
    uvec3 u = uvec3(c + ivec3(int(KEY_BIAS))) & uvec3(KEY_AXIS_MASK);
    return uint64_t(u.x) | (uint64_t(u.y) << KEY_BITS) | (uint64_t(u.z) << (2u * KEY_BITS));
}

ivec3 unpackBlockKey(uint64_t key) {
    uvec3 u = uvec3(uint(key & uint64_t(KEY_AXIS_MASK)), uint((key >> KEY_BITS) & uint64_t(KEY_AXIS_MASK)),
                    uint((key >> (2u * KEY_BITS)) & uint64_t(KEY_AXIS_MASK)));
    return ivec3(u) - ivec3(int(KEY_BIAS));
}

// The spatial hash of Teschner et al. (the one voxel hashing uses); the same code is in src/cpu.
uint hashSlot(ivec3 c) {
    uint h = (uint(c.x) * 73856093u) ^ (uint(c.y) * 19349669u) ^ (uint(c.z) * 83492791u);
    return h & (params.hashCapacity - 1u);
}

// Read-only lookup, valid in any dispatch after the one that inserted the key. Returns the hash slot
// or NO_BLOCK when the key is absent.
uint findSlot(ivec3 c) {
    if (!blockCoordInRange(c)) return NO_BLOCK;
    uint64_t key = packBlockKey(c);
    uint slot = hashSlot(c);
    for (uint probe = 0u; probe < HASH_MAX_PROBES; ++probe) {
        uint64_t k = hashKeys[slot];
        if (k == key) return slot;
        if (k == KEY_EMPTY) return NO_BLOCK;
        slot = (slot + 1u) & (params.hashCapacity - 1u);
    }
    return NO_BLOCK;
}

// Whether a block lies beyond the keep radius around the camera (its centre farther than keepRadius):
// such blocks are neither allocated nor kept. The CPU reference (src/cpu/reference_volume.cpp) repeats
// these float operations in this order.
bool blockOutsideKeepRadius(ivec3 c) {
    if (params.keepRadius <= 0.0) return false;
    float blockSize = params.voxelSize * float(BLOCK_SIDE);
    precise vec3 centre = (vec3(c) + 0.5) * blockSize;
    precise vec3 d = centre - vec3(frame.cameraToWorld[0].w, frame.cameraToWorld[1].w, frame.cameraToWorld[2].w);
    precise float distance2 = d.x * d.x + d.y * d.y + d.z * d.z;
    return distance2 > params.keepRadius * params.keepRadius;
}

// Block index of a block coordinate, or NO_BLOCK when it is not allocated.
uint findBlock(ivec3 c) {
    uint slot = findSlot(c);
    return slot == NO_BLOCK ? NO_BLOCK : hashValues[slot];
}

// ---- edge-vertex slots ---------------------------------------------------------------------------
// A slot is (block * 512 + cube) * 3 + axis (the owner cube's edge along that axis); the three axes live in
// three arrays.
uint edgeLoad(uint slot) {
    uint c = slot / 3u, a = slot % 3u;
    return a == 0u ? edgeVertexX[c] : (a == 1u ? edgeVertexY[c] : edgeVertexZ[c]);
}
void edgeStore(uint slot, uint v) {
    uint c = slot / 3u, a = slot % 3u;
    if (a == 0u) edgeVertexX[c] = v; else if (a == 1u) edgeVertexY[c] = v; else edgeVertexZ[c] = v;
}
void edgeStoreAtomic(uint slot, uint v) {
    uint c = slot / 3u, a = slot % 3u;
    if (a == 0u) atomicExchange(edgeVertexX[c], v); else if (a == 1u) atomicExchange(edgeVertexY[c], v); else atomicExchange(edgeVertexZ[c], v);
}
uint edgeCompSwap(uint slot, uint expected, uint v) {
    uint c = slot / 3u, a = slot % 3u;
    if (a == 0u) return atomicCompSwap(edgeVertexX[c], expected, v);
    if (a == 1u) return atomicCompSwap(edgeVertexY[c], expected, v);
    return atomicCompSwap(edgeVertexZ[c], expected, v);
}

// When a TSDF corner's sign or observed state (weight >= minMeshWeight) flips, the 8 cubes around it may
// change MC type: their bits are set in their block's retype mask, and the mesh passes retype only those
// cubes (docs/MESH.md). Cubes at -x/-y/-z of the block's low faces belong to the blocks behind, looked up
// here, per corner: few corners flip, and a workgroup-wide table would cost a barrier (expensive on
// lavapipe). Used by fusion and by block recycling (which zeroes or decays weights).
void markCornerRetype(uint block, uint local) {
    uvec3 l = uvec3(local % BLOCK_SIDE, (local / BLOCK_SIDE) % BLOCK_SIDE, local / (BLOCK_SIDE * BLOCK_SIDE));
    for (uint o = 0u; o < 8u; ++o) {
        uvec3 off = uvec3(o & 1u, (o >> 1) & 1u, (o >> 2) & 1u);
        uvec3 under = uvec3(lessThan(l, off));   // 1 on an axis where the cube lies in the block behind
        uint b = any(bvec3(under)) ? findBlock(blockCoords[block].xyz - ivec3(under)) : block;
        if (b == NO_BLOCK) continue;
        uvec3 c = (l + uvec3(BLOCK_SIDE) - off) % BLOCK_SIDE;
        uint cube = (c.z * BLOCK_SIDE + c.y) * BLOCK_SIDE + c.x;
        atomicOr(retypeMask[b * MASK_WORDS + cube / 32u], 1u << (cube % 32u));
    }
}

// ---- grid positions --------------------------------------------------------------------------------
// Index of corner (x, y, z) of a block in the voxel arrays: x fastest.
uint voxelIndex(uint block, uvec3 local) {
    return block * VOXELS_PER_BLOCK + (local.z * BLOCK_SIDE + local.y) * BLOCK_SIDE + local.x;
}

// x' = R x + t with R, t given as 3 rows of [R | t]; written out so that the order of the operations
// (and so the rounding) is the one src/cpu/reference.cpp uses.
vec3 transformPoint(vec4 rows[3], vec3 p) {
    precise vec3 q;
    q.x = rows[0].x * p.x + rows[0].y * p.y + rows[0].z * p.z + rows[0].w;
    q.y = rows[1].x * p.x + rows[1].y * p.y + rows[1].z * p.z + rows[1].w;
    q.z = rows[2].x * p.x + rows[2].y * p.y + rows[2].z * p.z + rows[2].w;
    return q;
}

uvec2 frameImageSize() { return uvec2(frame.imageSize & 0xFFFFu, frame.imageSize >> 16); }

// Aggregates a per-invocation count over the subgroup and adds it with one atomic. Must be called in
// uniform control flow (every invocation of the workgroup reaches it).
#define ADD_COUNTER(field, value)                                   \
    {                                                               \
        uint subgroupTotal_ = subgroupAdd(value);                   \
        if (subgroupElect() && subgroupTotal_ != 0u)                \
            atomicAdd(counters.field, subgroupTotal_);              \
    }
