#version 460
// One invocation before the delta passes: how far to compare (the most of each heap ever used, so that a
// rebuild that lowers the high water still reports what it removed) and the two dispatches' sizes.
#extension GL_GOOGLE_include_directive : require
#include "delta_common.glsl"

layout(local_size_x = 1) in;

void main() {
    deltaState.vertexRecords = 0u;
    deltaState.triangleRecords = 0u;
    if (counters.frameDeferred != 0u || counters.meshPending != 0u) {
        // A deferred frame, or a mesh with cubes still to re-mesh, reports nothing yet: the run that
        // completes it reports every change since the last report.
        deltaState.vertexDispatch[0] = 0u;
        deltaState.vertexDispatch[1] = 1u;
        deltaState.vertexDispatch[2] = 1u;
        deltaState.triangleDispatch[0] = 0u;
        deltaState.triangleDispatch[1] = 1u;
        deltaState.triangleDispatch[2] = 1u;
        return;
    }
    deltaState.vertexScan = max(deltaState.vertexScan, counters.vertexHighWater);
    deltaState.triangleScan = max(deltaState.triangleScan, counters.chunkHighWater * TRIANGLES_PER_CHUNK);
    deltaState.vertexDispatch[0] = (deltaState.vertexScan + WG_LIST - 1u) / WG_LIST;
    deltaState.vertexDispatch[1] = 1u;
    deltaState.vertexDispatch[2] = 1u;
    deltaState.triangleDispatch[0] = (deltaState.triangleScan + WG_LIST - 1u) / WG_LIST;
    deltaState.triangleDispatch[1] = 1u;
    deltaState.triangleDispatch[2] = 1u;
}
