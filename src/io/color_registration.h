// Colour from a camera beside the depth camera (docs/DATASETS.md, "Colour from a second camera"): every depth
// pixel with a measurement is lifted to 3D with the depth camera's intrinsics, moved into the colour camera by
// the depth-to-colour extrinsics, projected with the colour camera's intrinsics and the colour image sampled
// there (bilinearly). What the colour camera cannot see of that point gets no colour (black, as a pixel the
// colour camera misses): outside its image, behind it, or hidden behind a nearer surface from its viewpoint
// (a depth test against the nearest point projected into each colour pixel). This is depth-to-colour
// registration as RGB-D drivers do it; without a baseline (the extrinsics the identity) it is exact
// pixel-for-pixel when the two cameras' intrinsics are equal.
#pragma once

#include "core/types.h"

#include <Eigen/Core>

namespace vkmesh {

struct ColorCamera {
    Intrinsics intrinsics;  // width and height: the colour images' size
    // p_color = depthToColor * p_depth (metres, both cameras' optical frames: x right, y down, z forward).
    Eigen::Matrix4d depthToColor = Eigen::Matrix4d::Identity();
};

// Whether registering colour from `camera` onto the depth grid of `depth` is a plain copy: the same
// intrinsics and size, and no baseline or rotation.
bool isSameCamera(const ColorCamera& camera, const Intrinsics& depth);

// `color` (camera.intrinsics' size, RGB8) seen from the depth camera: an image of depthIntrinsics' size.
// Pixels without depth, or whose point the colour camera does not see, are black. The depth test finds what
// the depth image shows in front of a point from the colour camera's viewpoint; a surface only the colour camera
// sees (the side of an object, beyond the depth camera's silhouette) it cannot know of. occlusionTest false
// turns it off (tests measure what it removes). Throws Error when `color` or `depth` is not of the size its
// intrinsics say.
ColorImage registerColorToDepth(const ColorImage& color, const ColorCamera& camera, const DepthImage& depth,
                                const Intrinsics& depthIntrinsics, bool occlusionTest = true);

}  // namespace vkmesh
