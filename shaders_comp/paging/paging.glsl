// Paging (src/gpu/stages/paging_stage.h, docs/PAGING.md): the records of the blocks moved between GPU memory and the
// host, PAGE_RECORD_WORDS each (shared_layout.h), in the order of the block list the host wrote.
#ifndef VKMESH_PAGING_GLSL
#define VKMESH_PAGING_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_PAGE_RECORDS) buffer PageRecords { uint pageRecords[]; };
#endif
