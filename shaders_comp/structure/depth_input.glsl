// The frame's images, uploaded each frame into one buffer (one binding: the shared set is full): the depth
// image in metres (0 = no measurement), row-major, then, when the frame has colour (frameHasColor()), one
// RGBA8 word per pixel of the colour image registered to it (alpha 0 = no colour at that pixel).
#ifndef VKMESH_DEPTH_INPUT_GLSL
#define VKMESH_DEPTH_INPUT_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_DEPTH) readonly buffer FrameImages { uint frameImages[]; };

float depthAt(uint pixel) { return uintBitsToFloat(frameImages[pixel]); }
bool frameHasColor() { return (frame.imageSize & FRAME_HAS_COLOR) != 0u; }
// The pixel's colour word: red | green << 8 | blue << 16 | alpha << 24.
uint colorAt(uint pixel, uint pixelCount) { return frameImages[pixelCount + pixel]; }
#endif
