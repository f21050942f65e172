// The one header a program using vkmesh needs (installed as include/vkmesh/vkmesh.h; with
// find_package(vkmesh) and vkmesh::vkmesh linked, `#include <vkmesh.h>`). It pulls in the public pieces:
//   Reconstructor                 the embedding API: fuse frames, draw the mesh from its GPU buffers
//   vk::Context                   Vulkan instance/device (validation with VKMESH_VALIDATION=1)
//   gpu::GpuVolume                the TSDF volume: integrate depth frames, export the mesh
//   toMesh                        the exported mesh as a Mesh (for writePly, evaluation)
//   render::MeshRenderer          offscreen pictures of a mesh
//   readPly/writePly              meshes on disk
//   synth::SyntheticScene         synthetic depth with exact ground truth
// All of it is in vkmesh::vkmesh (Vulkan, no OpenCV). Image and dataset I/O is the vkmesh::io library, with
// headers of its own: io/dataset.h (Dataset: TUM, ICL-NUIM, Redwood, 7-Scenes), io/png.h, synth/tum_sequence.h,
// eval/evaluate.h.
// The other installed headers (core/, cpu/, eval/, ...) are the internals these include, or tools;
// they may change between versions.
#pragma once

#include "api/exported_mesh.h"
#include "api/reconstructor.h"
#include "core/mesh_delta.h"
#include "core/types.h"
#include "gpu/gpu_volume.h"
#include "io/delta_stream.h"
#include "io/ply.h"
#include "render/mesh_renderer.h"
#include "synth/synthetic_scene.h"
#include "vk/context.h"
