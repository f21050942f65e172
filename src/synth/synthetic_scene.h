// Synthetic RGB-D input with exact ground truth: an analytic scene (a signed distance function built from
// a few primitives), a sphere-tracing depth renderer with an optional Kinect-like noise model, smooth camera
// paths. The writer for the TUM RGB-D folder layout that vkmesh's dataset reader opens is synth/tum_sequence.h
// (part of the vkmesh_io library: it writes PNGs). Implemented in synth/shapes.cpp (primitives, the scene's
// sdf, sphere tracing), scenes.cpp (built-in scenes, camera paths), sensor_model.cpp (depth and colour
// rendering, noise) and ground_truth.cpp (sampleSurface).
//
// Conventions (the same as everywhere in vkmesh):
//   * world z is up; metres; poses are camera-to-world;
//   * camera frame: x right, y down, z forward (OpenCV/TUM); pixel (u, v) has its centre at integer
//     coordinates and looks along ((u - cx) / fx, (v - cy) / fy, 1);
//   * depth is the camera-frame z of the surface point (not the length of the ray), 0 = no measurement;
//   * sdf(p) > 0 in free space, < 0 inside solid matter.
#pragma once

#include "core/types.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace vkmesh::synth {

// The primitives a scene is made of. Every primitive lives in its own local frame (Object::objectToWorld).
enum class ObjectKind {
    RoomInterior,  // the inside of a box (walls, floor, ceiling) seen from within: free space is INSIDE the
                   // box of `halfExtents` centred on the local origin, matter is outside.
    HalfSpace,     // matter below the local plane z = 0, free space on the +z side (local z = plane normal).
    Sphere,        // centred on the local origin, `radius`.
    Torus,         // centred on the local origin around the local z axis: `radius` from the centre to the
                   // middle of the tube, `tubeRadius` the tube's own radius.
    RoundedBox,    // outer `halfExtents` along local x, y, z, edges and corners rounded with `edgeRadius`
                   // (0 gives a sharp-edged box).
    Cylinder,      // solid, flat-capped, around the local z axis: `radius`, from z = -halfHeight to +halfHeight.
};

// "room_interior", "half_space", "sphere", "torus", "rounded_box", "cylinder" (as written to scene.json).
std::string_view kindName(ObjectKind kind);

using Rgb = std::array<uint8_t, 3>;

// A solid texture: the colour of a surface point is a function of its position in the object's local frame,
// so it is exact at every point (a rendered pixel, a ground-truth sample) and needs no uv mapping.
//   Uniform  colour `a` everywhere;
//   Stripes  bands `period` metres wide across local axis `axis`, alternately a and b;
//   Checker  cubes of side `period` (a 3D checkerboard: squares on planes, patches on curved surfaces).
// `offset` shifts the pattern along every axis (metres), so that no flat face lies on a band boundary.
struct Texture {
    enum class Pattern { Uniform, Stripes, Checker };
    Pattern pattern = Pattern::Uniform;
    double period = 0.1;
    int axis = 2;
    double offset = 0;
    Rgb a{180, 180, 180}, b{180, 180, 180};
    Rgb at(const Eigen::Vector3d& localPoint) const;
};

// One primitive of a scene. Only the parameters its kind uses (see ObjectKind) are meaningful; the others
// stay 0.
struct Object {
    std::string name;
    ObjectKind kind = ObjectKind::Sphere;
    Eigen::Isometry3d objectToWorld = Eigen::Isometry3d::Identity();
    Eigen::Vector3d halfExtents = Eigen::Vector3d::Zero();
    double radius = 0;
    double tubeRadius = 0;
    double edgeRadius = 0;
    double halfHeight = 0;
    Texture texture;  // its surface colour (uniform grey unless set)

    Eigen::Vector3d center() const { return objectToWorld.translation(); }
    // Signed distance from a world point to this primitive alone (exact for every kind).
    double sdf(const Eigen::Vector3d& worldPoint) const;
    // Radius of a sphere around center() that contains all of the primitive; +infinity for the unbounded
    // kinds (RoomInterior, HalfSpace).
    double boundingRadius() const;
};

struct RenderOptions {
    float maxRange = 8;    // metres of camera-frame depth; pixels whose surface is farther (or absent) get 0
    bool noise = false;    // Kinect-like axial noise and dropout (see renderDepth)
    uint32_t seed = 1;     // the noise is a pure function of (seed, pixel), whatever the thread count
    // Colour only (renderDepth with a ColorImage): the camera's gain (1 = the texture's own colours) and
    // Gaussian per-pixel, per-channel noise of this sigma (0-255 units), drawn from (seed, pixel) apart from
    // the depth noise. The result is rounded and clamped to 0..255.
    double exposure = 1;
    double colorNoise = 0;
};

class SyntheticScene {
public:
    // The union of `objects`. Throws Error naming the object whose parameters are not positive and finite,
    // or whose name is empty or repeated.
    explicit SyntheticScene(std::vector<Object> objects);

    // A furnished room of 4 m x 3 m x 2.5 m, its floor at z = 0 around the world origin, turned 20 degrees
    // about the vertical so that no wall is aligned with a world axis. It holds, by name:
    //   "room"        RoomInterior: floor, four walls, ceiling;
    //   "sphere"      r = 0.35 m, floating (free-standing, fully observable);
    //   "torus"       R = 0.3 m, r = 0.1 m, floating, its axis tilted 55 degrees from vertical;
    //   "rounded_box" 0.5 x 0.36 x 0.5 m, 4 cm edge radius, standing on the floor;
    //   "ramp"        a 3 cm board slanted 30 degrees, its lower edge sunk into the floor;
    //   "thin_plate"  an upright 2.5 cm thick panel standing on the floor;
    //   "pole"        a 3 cm diameter, 1.5 m tall vertical cylinder standing on the floor.
    // No two objects touch, apart from the standing ones with the floor. Every object has its own colours
    // and pattern, from finer than a 2 cm voxel to coarse: room 25 cm beige/brown checker, sphere 8 mm
    // red/white stripes, torus 4 cm green/yellow checker, rounded_box 15 mm blue/white stripes, ramp 10 cm
    // orange/black checker, thin_plate 12 cm purple/grey stripes, pole uniform cyan.
    static SyntheticScene defaultRoom();
    // A gallery for drift and loop-closure tests: "hall", 13 m x 13 m x 3 m, its floor at z = 0 around the
    // world origin, turned -25 degrees about the vertical, with 24 distinct exhibits ("exhibit_00" ..
    // "exhibit_23": boxes, spheres, cylinders and tori, each of its own size, colours and pattern) on a ring of
    // radius ~5.3 m along the walls. Its path (PathKind::GalleryLoop) circles the middle looking outward, so
    // every view shows the floor, a wall and two or three exhibits, and most of it is new until the loop closes:
    // frame-to-model tracking drifts there (the default room, always seen whole, barely does). The hall's
    // 0.5 m checker and the exhibits are textured for the colour term, and nothing repeats around the ring, so
    // a place recognizer can tell where on the loop it is.
    static SyntheticScene gallery();
    // A false-loop trap: a room of 9 m x 4 m x 2.5 m, its floor at z = 0 around the world origin, turned 15
    // degrees about the vertical, with two identical groups of objects ("a_*" and "b_*": the same box,
    // sphere, cylinder and torus, same sizes, colours and patterns, in the same layout) 4.4 m apart along its
    // length, 1.1 m in front of a long wall. What surrounds them differs: a tall pole left of group a, a
    // slanted board right of group b, and a few other objects between the groups that keep tracking alive
    // while the camera travels (PathKind::TwinVisit). Seen from the same spot relative to either group, most
    // of the view is the same; a loop closer that trusts appearance alone closes a loop that is not there.
    static SyntheticScene twinGroups();
    // A single sphere in empty space (everything outside it is free space).
    static SyntheticScene singleSphere(const Eigen::Vector3d& center, double radius);
    // Free space where normal . p > offset, matter below; `normal` need not be unit length (it is normalised,
    // and offset is taken relative to the unit normal). Throws Error for a zero normal.
    static SyntheticScene slantedPlane(const Eigen::Vector3d& normal, double offset);

    // Minimum of the objects' signed distances: exact in free space, a lower bound of the magnitude inside
    // overlapping matter -- safe for sphere tracing.
    double sdf(const Eigen::Vector3d& p) const;
    // Unit outward (towards free space) normal by central differences of sdf(); zero where the gradient
    // vanishes (e.g. a sphere's centre).
    Eigen::Vector3d normal(const Eigen::Vector3d& p) const;
    // The colour at surface point p: the texture of the object nearest to p (smallest sdf).
    Rgb color(const Eigen::Vector3d& p) const;

    const std::vector<Object>& objects() const { return objects_; }
    // The object called `name`; throws Error naming it (and the names there are) when there is none.
    const Object& object(std::string_view name) const;

    // Renders camera-frame depth in metres, intrinsics.width x intrinsics.height pixels, by sphere tracing
    // every pixel (at most 256 steps, then bisection to well under 0.1 mm) on two threads.
    // With options.noise, a Kinect-like sensor model is applied (Nguyen, Izadi, Lovell 2012):
    //   * axial Gaussian noise, sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 metres;
    //   * dropout where the ray meets the surface at more than 80 degrees from its normal (and with a
    //     probability rising from 0 at 70 degrees to 0.5 at 80), and with probability 0.5 next to a depth
    //     discontinuity (a 4-neighbour empty or more than 4 % nearer/farther).
    // Quantisation to the sensor's 1/5000 m step is left to the writer. Throws Error for bad intrinsics or
    // a non-finite pose.
    // With `color`, also the colour image on the same grid: color(hit point) of the ray's exact hit (before
    // depth noise; a pixel whose depth the noise drops keeps its colour, as a real camera's would), scaled
    // by options.exposure plus options.colorNoise; black where the ray hits nothing. The depth is the same
    // with or without it.
    DepthImage renderDepth(const Intrinsics& intrinsics, const Pose& cameraToWorld,
                           const RenderOptions& options = {}, ColorImage* color = nullptr) const;

private:
    // A grid over the scene whose every cell lists the objects that can be nearest to some point of it: sdf()
    // takes the minimum over its point's cell's list, a few objects a step instead of all of them, and that is
    // the minimum over all objects exactly (buildNearestGrid says why), so a scene renders the same bits with
    // or without it. Empty for scenes of few objects; points outside it take every object.
    struct NearestGrid {
        Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the corner of cell (0, 0, 0)
        double cellSize = 0;
        Eigen::Vector3i cells = Eigen::Vector3i::Zero();
        std::vector<uint32_t> firstOfCell;  // cell c's objects: objects[firstOfCell[c] .. firstOfCell[c + 1])
        std::vector<uint16_t> objects;      // indices into objects_, ascending within a cell
    };
    void buildNearestGrid();

    std::vector<Object> objects_;
    std::vector<double> boundingRadii_;  // objects_[i].boundingRadius(), cached for the sdf() inner loop
    NearestGrid nearestGrid_;
};

// The default Kinect v1 calibration (fx = fy = 525, cx = 319.5, cy = 239.5 at 640 x 480) scaled to another
// image size, so that small test images see the same field of view.
Intrinsics kinectIntrinsics(int width = 640, int height = 480);

// Throws Error naming the value unless the intrinsics can be rendered: width and height > 0, fx and fy
// finite and non-zero (fy may be negative), cx and cy finite.
void validateIntrinsics(const Intrinsics& intrinsics);

enum class PathKind {
    Orbit,        // defaultRoom(): one smooth loop around the room's centre, the last frame one step before the first
    Revisit,      // defaultRoom(): the same loop driven three times, for loop-closure / revisiting tests: with
                  // frames a multiple of 3, frame i and frame i + frames / 3 have the same pose
    GalleryLoop,  // gallery(): a circle of radius 3.3 m around the hall's centre, looking outward at the walls
                  // and exhibits (so the model keeps growing: tracking drifts), 1.4 m +- 0.1 m high, pitched
                  // ~18 degrees down, with a gentle sway of radius, heading, pitch and roll. It starts at rest,
                  // reaching full speed over the first tenth of a lap; the lap takes 5/6 of the frames and the
                  // last sixth drives the start again: with frames a multiple of 6, frame i + 5 frames / 6 has
                  // frame i's pose for every i from frames / 12 on (the first pass is at full speed there).
    TwinVisit,    // twinGroups(): a first quarter swaying in front of group a (looking at it), a half travelling
                  // sideways along the room to group b (looking at the wall and the objects between), a last
                  // quarter in front of group b repeating the first quarter's poses relative to its group: with
                  // frames a multiple of 4, frame i + 3 frames / 4 is frame i's pose moved by the groups' offset.
};

// The name `vkmesh synth --path` takes: "orbit", "revisit", "gallery-loop", "twin-visit".
std::string_view pathName(PathKind kind);

// Camera-to-world poses for the scene the path is made for (see PathKind). Orbit and Revisit, in the default
// room: an ellipse of 3.2 m x 2.3 m around the room centre, camera height 1.5 m +- 0.2 m, looking at the
// objects (a gently wandering target ~0.55 m above the floor) with +-10 degrees of roll, so planes are seen
// from many angles. Every path is smooth (neighbouring frames close in position and angle) and every
// rotation proper (orthonormal, det +1). Throws Error for frames = 0.
std::vector<Pose> cameraPath(size_t frames, PathKind kind = PathKind::Orbit);

// The seed frame `frame` of a sequence seeded `seed` is rendered with (writeTumSequence, synth/tum_sequence.h):
// well mixed, so neighbouring frames' noise is unrelated.
uint32_t frameSeed(uint32_t seed, size_t frame);

// A surface point with its outward unit normal.
struct SurfaceSample {
    Eigen::Vector3d position;
    Eigen::Vector3d normal;
    Rgb color{0, 0, 0};  // the scene's colour there (SyntheticScene::color)
};

// Samples every object's surface uniformly by area, about `spacing` metres apart, keeping only points not
// inside or in contact with (within 0.1 mm of) another object. Unbounded kinds are sampled over a finite
// patch: a HalfSpace over 8 m x 8 m around the point of its plane nearest the world origin. Throws Error
// for spacing <= 0 or non-finite.
std::vector<SurfaceSample> sampleSurface(const SyntheticScene& scene, double spacing);

}  // namespace vkmesh::synth
