// Which blocks the recycling passes act on (docs/MESH.md, "Recycling blocks"). Both passes decide from the
// same data (the block's hash stamp, i.e. the last frame that touched it, and the camera), so they agree.
#ifndef VKMESH_RECYCLE_GLSL
#define VKMESH_RECYCLE_GLSL
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"

// A frame that tracking lost in its own submission (frameSkipped) retires and starves nothing: it is as if it
// had not been submitted.

// The block lies beyond the keep radius: its weights are zeroed and it is freed.
bool blockRetires(uint block) { return !frameSkipped() && blockOutsideKeepRadius(blockCoords[block].xyz); }

// The block has not been touched for starveAfterFrames frames: its weights decay, it is freed once all are 0.
bool blockStarves(uint block) {
    if (params.starveAfterFrames == 0u || frameSkipped()) return false;
    uint lastTouched = hashStamps[uint(blockCoords[block].w)];
    return frame.frameNumber - lastTouched >= params.starveAfterFrames;
}
#endif
