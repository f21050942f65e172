#include "gpu/structure/cube_mesh.h"

#include "core/marching_cubes.h"

namespace vkmesh::gpu {
namespace {
constexpr uint32_t kEdgeBindings[3] = {BINDING_EDGE_VERTEX_X, BINDING_EDGE_VERTEX_Y, BINDING_EDGE_VERTEX_Z};
constexpr const char* kEdgeNames[3] = {"edge vertex slots x", "edge vertex slots y", "edge vertex slots z"};
// A vertex of the heap that is free: every word all ones (its refcount is then DEAD_REFCOUNT).
constexpr uint32_t kDeadVertexWord = DEAD_REFCOUNT;
}  // namespace

const std::vector<uint32_t> CubeMesh::kCornerTags = {map::tag("cube"), map::tag("edgx"), map::tag("edgy"), map::tag("edgz")};

CubeMesh::CubeMesh(const vk::Context& context, const vk::BindingTable& table, uint32_t blockCapacity, uint32_t vertexCapacity,
                   uint32_t chunkCapacity, CounterBuffer& counters)
    : context_(context), table_(table), blockCapacity_(blockCapacity), vertexCapacity_(vertexCapacity), chunkCapacity_(chunkCapacity) {
    const VkDeviceSize cubes = VkDeviceSize(blockCapacity) * VOXELS_PER_BLOCK;
    cubeState_ = makeStorage(context, table, BINDING_CUBE_STATE, cubes * 4, "cube state");
    for (int a = 0; a < 3; ++a) edgeVertex_[a] = makeStorage(context, table, kEdgeBindings[a], cubes * 4, kEdgeNames[a]);
    ownedSlots_ = makeStorage(context, table, BINDING_OWNED_SLOTS, VkDeviceSize(blockCapacity) * OWNED_SLOT_WORDS * 4, "owned slot masks");
    // A vertex buffer too: tracking draws the model from the heap (ModelViewStage).
    vertices_ = makeStorage(context, table, BINDING_VERTICES, VkDeviceSize(vertexCapacity) * sizeof(Vertex), "vertex heap",
                            VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
    vertexOwner_ = makeStorage(context, table, BINDING_VERTEX_OWNER, VkDeviceSize(vertexCapacity) * 4, "vertex owners");
    vertexFree_ = makeStorage(context, table, BINDING_VERTEX_FREE, VkDeviceSize(vertexCapacity) * 4, "vertex free stack");
    chunkTriangles_ = makeStorage(context, table, BINDING_CHUNK_TRIANGLES, VkDeviceSize(chunkCapacity) * CHUNK_WORDS * 4, "triangle chunks");
    chunkFree_ = makeStorage(context, table, BINDING_CHUNK_FREE, VkDeviceSize(chunkCapacity) * 4, "chunk free stack");
    reset(counters);
}

void CubeMesh::reset(CounterBuffer& counters) {
    vk::CommandRecorder recorder(context_);
    VkCommandBuffer cmd = recorder.begin();
    vkCmdFillBuffer(cmd, cubeState_.handle(), 0, VK_WHOLE_SIZE, 0);
    for (const vk::Buffer& b : edgeVertex_) vkCmdFillBuffer(cmd, b.handle(), 0, VK_WHOLE_SIZE, EMPTY_SLOT);
    vkCmdFillBuffer(cmd, ownedSlots_.handle(), 0, VK_WHOLE_SIZE, 0);   // every slot EMPTY
    vkCmdFillBuffer(cmd, vertices_.handle(), 0, VK_WHOLE_SIZE, kDeadVertexWord);
    vkCmdFillBuffer(cmd, chunkTriangles_.handle(), 0, VK_WHOLE_SIZE, INVALID_INDEX);   // every triangle slot empty
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
    fillFreeStack(context_, vertexFree_, vertexCapacity_);
    fillFreeStack(context_, chunkFree_, chunkCapacity_);
    counters.update([&](Counters& k) {
        k.vertexFreeTop = vertexCapacity_;
        k.verticesInUse = k.vertexHighWater = 0;
        k.chunkFreeTop = chunkCapacity_;
        k.chunksInUse = k.chunkHighWater = 0;
        k.liveTriangles = 0;
    });
}

void CubeMesh::growCubes(uint32_t blockCapacity) {
    if (blockCapacity <= blockCapacity_) return;
    const VkDeviceSize cubes = VkDeviceSize(blockCapacity) * VOXELS_PER_BLOCK;
    std::vector<vk::Buffer> retired;
    vk::CommandRecorder recorder(context_);
    VkCommandBuffer cmd = recorder.begin();
    growStorage(cmd, context_, table_, BINDING_CUBE_STATE, cubeState_, cubes * 4, 0, retired);
    for (int a = 0; a < 3; ++a) growStorage(cmd, context_, table_, kEdgeBindings[a], edgeVertex_[a], cubes * 4, EMPTY_SLOT, retired);
    growStorage(cmd, context_, table_, BINDING_OWNED_SLOTS, ownedSlots_, VkDeviceSize(blockCapacity) * OWNED_SLOT_WORDS * 4, 0, retired);
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
    blockCapacity_ = blockCapacity;
}

void CubeMesh::growHeaps(uint32_t vertexCapacity, uint32_t chunkCapacity, CounterBuffer& counters) {
    vertexCapacity = std::max(vertexCapacity, vertexCapacity_);
    chunkCapacity = std::max(chunkCapacity, chunkCapacity_);
    if (vertexCapacity == vertexCapacity_ && chunkCapacity == chunkCapacity_) return;
    const Counters k = counters.read();
    std::vector<vk::Buffer> retired;
    vk::CommandRecorder recorder(context_);
    VkCommandBuffer cmd = recorder.begin();
    if (vertexCapacity > vertexCapacity_) {
        // New entries: free vertices (refcount DEAD), owners unset.
        growStorage(cmd, context_, table_, BINDING_VERTICES, vertices_, VkDeviceSize(vertexCapacity) * sizeof(Vertex), kDeadVertexWord, retired,
                    VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
        growStorage(cmd, context_, table_, BINDING_VERTEX_OWNER, vertexOwner_, VkDeviceSize(vertexCapacity) * 4, 0, retired);
    }
    if (chunkCapacity > chunkCapacity_)   // new chunks: no triangle
        growStorage(cmd, context_, table_, BINDING_CHUNK_TRIANGLES, chunkTriangles_, VkDeviceSize(chunkCapacity) * CHUNK_WORDS * 4,
                    INVALID_INDEX, retired);
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
    retired.clear();
    if (vertexCapacity > vertexCapacity_)
        growFreeStack(context_, table_, BINDING_VERTEX_FREE, vertexFree_, k.vertexFreeTop, vertexCapacity_, vertexCapacity);
    if (chunkCapacity > chunkCapacity_)
        growFreeStack(context_, table_, BINDING_CHUNK_FREE, chunkFree_, k.chunkFreeTop, chunkCapacity_, chunkCapacity);
    const uint32_t addedVertices = vertexCapacity - vertexCapacity_, addedChunks = chunkCapacity - chunkCapacity_;
    counters.update([&](Counters& c) {
        c.vertexFreeTop += addedVertices;
        c.chunkFreeTop += addedChunks;
    });
    vertexCapacity_ = vertexCapacity;
    chunkCapacity_ = chunkCapacity;
}

MeshStateSnapshot CubeMesh::download(const Counters& counters) const {
    MeshStateSnapshot s;
    s.counters = counters;
    s.vertices.resize(vertexCapacity_);
    vk::downloadFromBuffer(context_, vertices_, s.vertices.data(), s.vertices.size() * sizeof(Vertex));
    s.vertexOwner.resize(vertexCapacity_);
    vk::downloadFromBuffer(context_, vertexOwner_, s.vertexOwner.data(), s.vertexOwner.size() * 4);
    const size_t cubes = size_t(blockCapacity_) * VOXELS_PER_BLOCK;
    s.edgeVertex.resize(cubes * 3);
    std::vector<uint32_t> axis(cubes);
    for (int a = 0; a < 3; ++a) {
        vk::downloadFromBuffer(context_, edgeVertex_[a], axis.data(), cubes * 4);
        for (size_t i = 0; i < cubes; ++i) s.edgeVertex[i * 3 + a] = axis[i];
    }
    s.ownedSlots = downloadWords(context_, ownedSlots_, size_t(blockCapacity_) * OWNED_SLOT_WORDS);
    std::vector<uint32_t> state(cubes), chunks(size_t(chunkCapacity_) * CHUNK_WORDS);
    vk::downloadFromBuffer(context_, cubeState_, state.data(), state.size() * 4);
    vk::downloadFromBuffer(context_, chunkTriangles_, chunks.data(), chunks.size() * 4);
    const MarchingCubesTables& tables = marchingCubesTables();
    for (uint32_t st : state) {
        const uint32_t chunk = st >> CUBE_CHUNK_SHIFT;   // chunk index + 1, 0 = none
        if (!chunk) continue;
        for (uint32_t t = 0; t < tables.triangleCount[st & CUBE_TYPE_MASK]; ++t) {
            const uint32_t* tri = &chunks[size_t(chunk - 1) * CHUNK_WORDS + 3 * t];
            if (tri[0] != INVALID_INDEX) s.liveTriangles.push_back({tri[0], tri[1], tri[2]});
        }
    }
    return s;
}

std::array<uint64_t, 256> CubeMesh::surfaceCubeTypes() const {
    std::vector<uint32_t> state(size_t(blockCapacity_) * VOXELS_PER_BLOCK);
    vk::downloadFromBuffer(context_, cubeState_, state.data(), state.size() * 4);
    std::array<uint64_t, 256> histogram{};
    for (uint32_t st : state)
        if ((st >> CUBE_CHUNK_SHIFT) != 0) ++histogram[st & CUBE_TYPE_MASK];
    return histogram;
}

void CubeMesh::save(map::MapData& map, const std::vector<uint32_t>& blocks, const Counters& k) const {
    const vk::Buffer* arrays[4] = {&cubeState_, &edgeVertex_[0], &edgeVertex_[1], &edgeVertex_[2]};
    for (int i = 0; i < 4; ++i) {
        map::CornerArray out{kCornerTags[i], std::vector<uint32_t>(blocks.size() * VOXELS_PER_BLOCK)};
        downloadRecords(context_, *arrays[i], 4 * VOXELS_PER_BLOCK, blocks, out.words.data());
        map.cornerArrays.push_back(std::move(out));
    }
    map.vertexFree = map::FreeStack::fromEntries(downloadWords(context_, vertexFree_, k.vertexFreeTop), vertexCapacity_);
    map.chunkFree = map::FreeStack::fromEntries(downloadWords(context_, chunkFree_, k.chunkFreeTop), chunkCapacity_);
    // Every index at or above the untouched run is free (never used since the heap was last reset): only the
    // heap below it is stored.
    const uint32_t vertices = map.vertexFree.firstUntouched, chunks = map.chunkFree.firstUntouched;
    map.vertices.resize(vertices);
    if (vertices) vk::downloadFromBuffer(context_, vertices_, map.vertices.data(), VkDeviceSize(vertices) * sizeof(Vertex));
    map.vertexOwners = downloadWords(context_, vertexOwner_, vertices);
    map.chunkWords = downloadWords(context_, chunkTriangles_, size_t(chunks) * CHUNK_WORDS);
}

void CubeMesh::load(const map::MapData& map, const std::vector<uint32_t>& blocks, CounterBuffer& counters) {
    const vk::Buffer* arrays[4] = {&cubeState_, &edgeVertex_[0], &edgeVertex_[1], &edgeVertex_[2]};
    for (int i = 0; i < 4; ++i) uploadRecords(context_, *arrays[i], 4 * VOXELS_PER_BLOCK, blocks, map.corners(kCornerTags[i])->words.data());
    // The owned-slot masks follow from the edge slots (a bit per slot that holds a vertex); the other blocks'
    // masks are 0 already (a new mesh).
    std::vector<uint32_t> owned(blocks.size() * OWNED_SLOT_WORDS, 0);
    for (uint32_t a = 0; a < 3; ++a) {
        const std::vector<uint32_t>& slots = map.corners(kCornerTags[1 + a])->words;
        for (size_t b = 0; b < blocks.size(); ++b)
            for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube)
                if (slots[b * VOXELS_PER_BLOCK + cube] != EMPTY_SLOT)
                    owned[b * OWNED_SLOT_WORDS + a * MASK_WORDS + cube / 32] |= 1u << (cube % 32);
    }
    uploadRecords(context_, ownedSlots_, 4 * OWNED_SLOT_WORDS, blocks, owned.data());
    if (!map.vertices.empty())
        vk::uploadToBuffer(context_, vertices_, map.vertices.data(), VkDeviceSize(map.vertices.size()) * sizeof(Vertex));
    uploadWords(context_, vertexOwner_, map.vertexOwners);
    uploadWords(context_, chunkTriangles_, map.chunkWords);
    const std::vector<uint32_t> vertexStack = map.vertexFree.entries(vertexCapacity_), chunkStack = map.chunkFree.entries(chunkCapacity_);
    uploadWords(context_, vertexFree_, vertexStack);
    uploadWords(context_, chunkFree_, chunkStack);
    counters.update([&](Counters& k) {
        k.vertexFreeTop = uint32_t(vertexStack.size());
        k.chunkFreeTop = uint32_t(chunkStack.size());
    });
}

}  // namespace vkmesh::gpu
