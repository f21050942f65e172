// The built-in synthetic scenes (default room, gallery, twin groups, single sphere, slanted plane) and the
// camera paths made for them (PathKind).
#include "synth/synthetic_scene.h"
#include "synth/synthetic_scene_internal.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace vkmesh::synth {

using detail::degrees;
using detail::kPi;

namespace {

Eigen::Matrix3d rotationAbout(const Eigen::Vector3d& axis, double angleRadians) {
    return Eigen::AngleAxisd(angleRadians, axis.normalized()).toRotationMatrix();
}

Eigen::Isometry3d placement(const Eigen::Vector3d& translation, const Eigen::Matrix3d& rotation) {
    Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
    result.linear() = rotation;
    result.translation() = translation;
    return result;
}

std::string formatVector(const Eigen::Vector3d& v) {
    std::ostringstream out;
    out << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
    return out.str();
}

// ---------------------------------------------------------------------------------------------------------
// The default room. Everything is laid out in the room's own frame (x along the 4 m side, y along the 3 m
// side, z up, floor at z = 0, origin at the floor centre) and then turned about the vertical, so that the
// renderer and the fusion code are never helped by planes aligned with the world axes.
constexpr double kRoomYawDegrees = 20.0;
const Eigen::Vector3d kRoomHalfExtents(2.0, 1.5, 1.25);

Eigen::Isometry3d turnedAboutVertical(double yawDegrees) {
    return placement(Eigen::Vector3d::Zero(), rotationAbout(Eigen::Vector3d::UnitZ(), degrees(yawDegrees)));
}

Eigen::Isometry3d roomToWorld() { return turnedAboutVertical(kRoomYawDegrees); }

// The camera orbit, in the room frame. The objects stand within about 1 m of the centre, so this ellipse keeps
// the camera at least ~0.5 m from every object and ~0.35 m from every wall.
constexpr double kOrbitSemiAxisX = 1.6;
constexpr double kOrbitSemiAxisY = 1.15;
constexpr double kCameraHeight = 1.5;
constexpr double kCameraHeightSwing = 0.2;
constexpr double kLookAtHeight = 0.55;
constexpr double kRollAmplitudeDegrees = 10.0;
constexpr int kRevisitLaps = 3;

// ---------------------------------------------------------------------------------------------------------
// The gallery (SyntheticScene::gallery, PathKind::GalleryLoop), laid out in the hall's own frame (origin at the
// floor centre) and turned like the default room. The exhibits' ring lies between the camera's circle and the
// walls: ~1.2 m in front of the camera, the wall behind them 2 m (mid-wall) to 4 m (corner) away.
constexpr double kGalleryYawDegrees = -25.0;
const Eigen::Vector3d kGalleryHalfExtents(6.5, 6.5, 1.5);
constexpr int kGalleryExhibits = 24;
constexpr double kExhibitRingRadius = 5.3;
constexpr double kGalleryLoopRadius = 3.3;
constexpr double kGalleryCameraHeight = 1.4;
constexpr double kGalleryPitchDegrees = 18.0;
// A lap is this share of the frames; the rest drives the start again, for a loop closer to recognise.
constexpr double kGalleryLapShare = 5.0 / 6.0;
constexpr double kGalleryStartShare = 0.1;

// The twin-groups room (SyntheticScene::twinGroups, PathKind::TwinVisit), in its own frame. The groups are
// 18 checker cells of the walls apart, so even the wall behind them looks the same.
constexpr double kTwinRoomYawDegrees = 15.0;
const Eigen::Vector3d kTwinRoomHalfExtents(4.5, 2.0, 1.25);
constexpr double kTwinCheckerPeriod = 0.25;
const Eigen::Vector3d kTwinGroupA(-2.25, 0.9, 0.0);
const Eigen::Vector3d kTwinGroupB(2.25, 0.9, 0.0);
// Where the camera looks at a group from, relative to the group's centre, and the point it looks at.
const Eigen::Vector3d kTwinViewpoint(0.0, -1.9, 1.45);
const Eigen::Vector3d kTwinLookAt(0.0, 0.0, 0.6);

// A camera at `eye` looking at `target` (world z up: the image's x axis stays horizontal), then turned
// `rollRadians` about its viewing direction. Camera axes: x right, y down, z forward.
Eigen::Matrix3d lookingAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, double rollRadians) {
    const Eigen::Vector3d forward = (target - eye).normalized();
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d down = forward.cross(right);
    Eigen::Matrix3d rotation;
    rotation << right, down, forward;
    return rotation * rotationAbout(Eigen::Vector3d::UnitZ(), rollRadians);
}

// A number in [0, 1) that varies irregularly with `index` (a golden-ratio sequence), so generated objects
// differ from their neighbours without a hand-written table; `salt` gives another, unrelated sequence.
double spread(int index, double salt) {
    const double value = 0.5 + (index + 1) * 0.6180339887498949 * (1.0 + salt);
    return value - std::floor(value);
}

// Exhibit `index` of the gallery, in the hall's frame: its kind cycles box, sphere, cylinder, torus, and its
// size, height, turn, colours and pattern all vary, so no two exhibits look alike.
Object galleryExhibit(int index) {
    static constexpr std::array<Rgb, 12> kPalette{{{220, 40, 40},   {240, 240, 240}, {40, 160, 60},  {230, 210, 40},
                                                   {40, 70, 200},   {240, 130, 20},  {30, 30, 30},   {150, 60, 170},
                                                   {0, 200, 210},   {250, 150, 190}, {120, 80, 40},  {130, 130, 130}}};
    const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
    const double angle = 2 * kPi * index / kGalleryExhibits + 0.03 * std::sin(2.3 * index);
    const double ring = kExhibitRingRadius + 0.25 * std::sin(1.7 * index);
    const Eigen::Vector3d radial(std::cos(angle), std::sin(angle), 0);
    const double u = spread(index, 0.0), v = spread(index, 0.37), w = spread(index, 0.71);

    char name[16];
    std::snprintf(name, sizeof name, "exhibit_%02d", index);
    Object object{.name = name};
    const Texture::Pattern pattern = (index / 4) % 2 == 0 ? Texture::Pattern::Stripes : Texture::Pattern::Checker;
    const Rgb a = kPalette[index % kPalette.size()], b = kPalette[(index * 5 + 3 + index / 12) % kPalette.size()];
    // Odd sub-millimetre offsets keep flat faces off band edges (see defaultRoom()).
    object.texture = {pattern, 0.03 + 0.12 * v, index % 3, 0.00137 * (index + 1), a, b == a ? kPalette[1] : b};

    Eigen::Vector3d center = ring * radial;
    Eigen::Matrix3d rotation = rotationAbout(up, angle + degrees(37.0 * index));
    switch (index % 4) {
        case 0:  // a plinth standing on the floor
            object.kind = ObjectKind::RoundedBox;
            object.halfExtents = {0.18 + 0.12 * u, 0.18 + 0.1 * w, 0.3 + 0.35 * v};
            object.edgeRadius = 0.03;
            center.z() = object.halfExtents.z();
            break;
        case 1:  // a floating ball
            object.kind = ObjectKind::Sphere;
            object.radius = 0.22 + 0.12 * u;
            center.z() = 0.55 + 0.6 * w;
            rotation = Eigen::Matrix3d::Identity();
            break;
        case 2:  // a column standing on the floor
            object.kind = ObjectKind::Cylinder;
            object.radius = 0.1 + 0.12 * u;
            object.halfHeight = 0.4 + 0.45 * w;
            center.z() = object.halfHeight;
            break;
        default:  // a floating ring, tilted so that its hole shows from the middle of the hall
            object.kind = ObjectKind::Torus;
            object.radius = 0.25 + 0.1 * u;
            object.tubeRadius = 0.06 + 0.04 * w;
            center.z() = 0.9 + 0.4 * v;
            rotation = rotationAbout(up, angle) * rotationAbout(Eigen::Vector3d::UnitY(), degrees(50 + 30 * w));
            break;
    }
    object.objectToWorld = placement(center, rotation);
    return object;
}

// The four objects of one twin group, centred on `center` (twin-room frame, on the floor), named prefix_*:
// both groups are built by this one function, so they are identical but for where they stand.
void addTwinGroup(const std::string& prefix, const Eigen::Vector3d& center, std::vector<Object>& objects) {
    const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
    Object box{.name = prefix + "_box", .kind = ObjectKind::RoundedBox};
    box.halfExtents = {0.25, 0.2, 0.3};
    box.edgeRadius = 0.03;
    box.texture = {Texture::Pattern::Stripes, 0.03, 0, 0.00313, {40, 70, 200}, {250, 250, 250}};
    box.objectToWorld = placement(center + Eigen::Vector3d(-0.45, 0.1, box.halfExtents.z()), rotationAbout(up, degrees(20)));
    objects.push_back(box);

    Object sphere{.name = prefix + "_sphere", .kind = ObjectKind::Sphere};
    sphere.radius = 0.22;
    sphere.texture = {Texture::Pattern::Checker, 0.06, 2, 0.00731, {220, 40, 40}, {230, 210, 40}};
    sphere.objectToWorld = placement(center + Eigen::Vector3d(0.05, -0.15, 0.75), Eigen::Matrix3d::Identity());
    objects.push_back(sphere);

    Object cylinder{.name = prefix + "_cylinder", .kind = ObjectKind::Cylinder};
    cylinder.radius = 0.15;
    cylinder.halfHeight = 0.45;
    cylinder.texture = {Texture::Pattern::Stripes, 0.05, 2, 0.0219, {40, 160, 60}, {240, 240, 240}};
    cylinder.objectToWorld = placement(center + Eigen::Vector3d(0.5, 0.2, cylinder.halfHeight), Eigen::Matrix3d::Identity());
    objects.push_back(cylinder);

    Object torus{.name = prefix + "_torus", .kind = ObjectKind::Torus};
    torus.radius = 0.25;
    torus.tubeRadius = 0.07;
    torus.texture = {Texture::Pattern::Checker, 0.04, 2, 0.00537, {240, 130, 20}, {30, 30, 30}};
    torus.objectToWorld = placement(center + Eigen::Vector3d(0.0, 0.35, 1.3), rotationAbout(Eigen::Vector3d::UnitX(), degrees(60)));
    objects.push_back(torus);
}

// The default room's orbit (PathKind::Orbit, Revisit), `laps` times around in `frames` frames.
std::vector<Pose> roomOrbit(size_t frames, int laps) {
    const Eigen::Isometry3d toWorld = roomToWorld();
    std::vector<Pose> poses;
    poses.reserve(frames);
    for (size_t i = 0; i < frames; ++i) {
        // Every term is periodic in the phase, so the loop closes smoothly and laps coincide.
        const double phase = 2 * kPi * laps * static_cast<double>(i) / static_cast<double>(frames);
        const Eigen::Vector3d eye(kOrbitSemiAxisX * std::cos(phase), kOrbitSemiAxisY * std::sin(phase),
                                  kCameraHeight + kCameraHeightSwing * std::sin(2 * phase));
        const Eigen::Vector3d target(0.15 * std::cos(3 * phase), 0.1 * std::sin(2 * phase), kLookAtHeight);
        const double roll = degrees(kRollAmplitudeDegrees) * std::sin(3 * phase + 0.5);
        poses.push_back((toWorld * placement(eye, lookingAt(eye, target, roll))).matrix());
    }
    return poses;
}

// PathKind::GalleryLoop: around the hall's centre, looking outward, with a sway periodic in the lap so the
// second pass over the start repeats the first exactly.
std::vector<Pose> galleryLoop(size_t frames) {
    const Eigen::Isometry3d toWorld = turnedAboutVertical(kGalleryYawDegrees);
    // The camera starts at rest and reaches its speed over the first kGalleryStartShare of a lap (phase
    // quadratic, then linear: smooth), as a real one would, so frame 1 is not a jump that tracking only half
    // catches up with (an offset at the start, not drift). The lap then ends at 2 pi, and the frames after it
    // drive the start again at full speed (the same poses as functions of the phase).
    const double lapFrames = kGalleryLapShare * static_cast<double>(frames);
    const double rampFrames = kGalleryStartShare * lapFrames;
    const double speed = 2 * kPi / (lapFrames - 0.5 * rampFrames);  // radians per frame once at speed
    std::vector<Pose> poses;
    poses.reserve(frames);
    for (size_t i = 0; i < frames; ++i) {
        const double t = static_cast<double>(i);
        const double phase = t < rampFrames ? speed * t * t / (2 * rampFrames) : speed * (t - 0.5 * rampFrames);
        const double radius = kGalleryLoopRadius + 0.15 * std::sin(4 * phase);
        const Eigen::Vector3d eye(radius * std::cos(phase), radius * std::sin(phase),
                                  kGalleryCameraHeight + 0.1 * std::sin(5 * phase));
        const double heading = phase + degrees(10) * std::sin(2 * phase + 0.3);
        const double pitch = degrees(kGalleryPitchDegrees + 4 * std::sin(3 * phase + 1.0));
        const Eigen::Vector3d forward(std::cos(heading) * std::cos(pitch), std::sin(heading) * std::cos(pitch),
                                      -std::sin(pitch));
        const double roll = degrees(5) * std::sin(4 * phase + 0.5);
        poses.push_back((toWorld * placement(eye, lookingAt(eye, eye + forward, roll))).matrix());
    }
    return poses;
}

// 0 at t = 0, 1 at t = 1, with zero speed at both ends.
double smoothstep(double t) { return t * t * (3 - 2 * t); }

// PathKind::TwinVisit: a quarter at group a, a half travelling, a quarter at group b. The visits' sway
// starts and ends at rest at the viewpoint, where the travel starts and ends at rest too, so the path is
// smooth; it depends only on the time within the visit, so both visits see their group alike.
std::vector<Pose> twinVisit(size_t frames) {
    const Eigen::Isometry3d toWorld = turnedAboutVertical(kTwinRoomYawDegrees);
    std::vector<Pose> poses;
    poses.reserve(frames);
    for (size_t i = 0; i < frames; ++i) {
        const double s = static_cast<double>(i) / static_cast<double>(frames);  // [0, 1)
        Eigen::Vector3d group = kTwinGroupA;
        double visitTime = -1;  // within a visit: [0, 1); travelling: -1
        if (s < 0.25) {
            visitTime = s / 0.25;
        } else if (s >= 0.75) {
            group = kTwinGroupB;
            visitTime = (s - 0.75) / 0.25;
        } else {
            group = kTwinGroupA + smoothstep((s - 0.25) / 0.5) * (kTwinGroupB - kTwinGroupA);
        }
        Eigen::Vector3d eye = group + kTwinViewpoint, target = group + kTwinLookAt;
        double roll = 0;
        if (visitTime >= 0) {
            const double envelope = std::sin(kPi * visitTime);  // 0 at both ends, so is its effect's speed
            eye += envelope * Eigen::Vector3d(0.45 * std::sin(2 * kPi * visitTime), 0.2 * envelope,
                                              0.15 * std::sin(4 * kPi * visitTime));
            target += envelope * Eigen::Vector3d(-0.15 * std::sin(2 * kPi * visitTime), 0, 0.1 * envelope);
            roll = degrees(6) * envelope * std::sin(2 * kPi * visitTime + 0.5);
        }
        poses.push_back((toWorld * placement(eye, lookingAt(eye, target, roll))).matrix());
    }
    return poses;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
SyntheticScene SyntheticScene::defaultRoom() {
    const Eigen::Isometry3d toWorld = roomToWorld();
    const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
    auto inRoom = [&](const Eigen::Vector3d& roomPosition, const Eigen::Matrix3d& roomRotation) {
        return toWorld * placement(roomPosition, roomRotation);
    };
    std::vector<Object> objects;

    Object room{.name = "room", .kind = ObjectKind::RoomInterior};
    room.objectToWorld = inRoom({0, 0, kRoomHalfExtents.z()}, Eigen::Matrix3d::Identity());
    room.halfExtents = kRoomHalfExtents;
    // Offsets are odd fractions of a millimetre so that no flat face and no row of GT samples (laid out on
    // round-number grids) sits on a band edge, where float rounding of a position would flip its colour.
    room.texture = {Texture::Pattern::Checker, 0.25, 2, 0.0537, {200, 180, 140}, {90, 70, 50}};
    objects.push_back(room);

    // Floating, so that every part of it is in free space and can be seen.
    Object sphere{.name = "sphere", .kind = ObjectKind::Sphere};
    sphere.objectToWorld = inRoom({0.55, 0.25, 0.75}, Eigen::Matrix3d::Identity());
    sphere.radius = 0.35;
    sphere.texture = {Texture::Pattern::Stripes, 0.008, 2, 0.00137, {220, 40, 40}, {240, 240, 240}};  // finer than a voxel
    objects.push_back(sphere);

    // Floating and tilted, so that its hole and both faces show from the orbit.
    Object torus{.name = "torus", .kind = ObjectKind::Torus};
    torus.objectToWorld = inRoom({-0.6, 0.2, 0.85}, rotationAbout(up, degrees(30)) *
                                                        rotationAbout(Eigen::Vector3d::UnitX(), degrees(55)));
    torus.radius = 0.3;
    torus.tubeRadius = 0.1;
    torus.texture = {Texture::Pattern::Checker, 0.04, 2, 0.00731, {40, 160, 60}, {230, 210, 40}};
    objects.push_back(torus);

    Object roundedBox{.name = "rounded_box", .kind = ObjectKind::RoundedBox};
    roundedBox.halfExtents = {0.25, 0.18, 0.25};
    roundedBox.edgeRadius = 0.04;
    roundedBox.texture = {Texture::Pattern::Stripes, 0.015, 0, 0.00313, {40, 70, 200}, {250, 250, 250}};
    roundedBox.objectToWorld = inRoom({0.1, -0.45, roundedBox.halfExtents.z()}, rotationAbout(up, degrees(30)));
    objects.push_back(roundedBox);

    // A 3 cm board rising at 30 degrees along its local x; its centre height sinks the lower edge ~1 cm into
    // the floor, as a ramp resting on the ground would.
    Object ramp{.name = "ramp", .kind = ObjectKind::RoundedBox};
    ramp.halfExtents = {0.45, 0.25, 0.015};
    ramp.texture = {Texture::Pattern::Checker, 0.1, 2, 0.0219, {240, 130, 20}, {30, 30, 30}};
    ramp.objectToWorld = inRoom({-0.75, -0.5, 0.225}, rotationAbout(up, degrees(-15)) *
                                                          rotationAbout(Eigen::Vector3d::UnitY(), degrees(-30)));
    objects.push_back(ramp);

    // The thin part: an upright panel 2.5 cm thick, only a few voxels across at usual voxel sizes.
    Object plate{.name = "thin_plate", .kind = ObjectKind::RoundedBox};
    plate.halfExtents = {0.25, 0.0125, 0.35};
    plate.texture = {Texture::Pattern::Stripes, 0.12, 2, 0.0313, {150, 60, 170}, {120, 120, 120}};
    plate.objectToWorld = inRoom({0.05, 0.8, plate.halfExtents.z()}, rotationAbout(up, degrees(10)));
    objects.push_back(plate);

    Object pole{.name = "pole", .kind = ObjectKind::Cylinder};
    pole.radius = 0.015;
    pole.halfHeight = 0.75;
    pole.texture = {Texture::Pattern::Uniform, 0.1, 2, 0, {0, 200, 210}, {0, 200, 210}};
    // Between the orbit and the sphere (14 cm clear of it), so it often occludes: a thin occluder in front.
    pole.objectToWorld = inRoom({0.75, -0.2, pole.halfHeight}, Eigen::Matrix3d::Identity());
    objects.push_back(pole);

    return SyntheticScene(std::move(objects));
}

SyntheticScene SyntheticScene::gallery() {
    const Eigen::Isometry3d toWorld = turnedAboutVertical(kGalleryYawDegrees);
    std::vector<Object> objects;
    Object hall{.name = "hall", .kind = ObjectKind::RoomInterior};
    hall.objectToWorld = toWorld * placement({0, 0, kGalleryHalfExtents.z()}, Eigen::Matrix3d::Identity());
    hall.halfExtents = kGalleryHalfExtents;
    hall.texture = {Texture::Pattern::Checker, 0.5, 2, 0.0537, {210, 200, 170}, {110, 90, 70}};
    objects.push_back(hall);
    for (int index = 0; index < kGalleryExhibits; ++index) {
        Object exhibit = galleryExhibit(index);
        exhibit.objectToWorld = toWorld * exhibit.objectToWorld;
        objects.push_back(std::move(exhibit));
    }
    return SyntheticScene(std::move(objects));
}

SyntheticScene SyntheticScene::twinGroups() {
    const Eigen::Isometry3d toWorld = turnedAboutVertical(kTwinRoomYawDegrees);
    const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
    std::vector<Object> objects;
    Object room{.name = "room", .kind = ObjectKind::RoomInterior};
    room.objectToWorld = placement({0, 0, kTwinRoomHalfExtents.z()}, Eigen::Matrix3d::Identity());
    room.halfExtents = kTwinRoomHalfExtents;
    room.texture = {Texture::Pattern::Checker, kTwinCheckerPeriod, 2, 0.0537, {200, 180, 140}, {90, 70, 50}};
    objects.push_back(room);
    addTwinGroup("a", kTwinGroupA, objects);
    addTwinGroup("b", kTwinGroupB, objects);

    // What tells the groups apart: a pole left of a, a slanted board right of b.
    Object pole{.name = "pole_a", .kind = ObjectKind::Cylinder};
    pole.radius = 0.04;
    pole.halfHeight = 1.0;
    pole.texture = {Texture::Pattern::Uniform, 0.1, 2, 0, {0, 200, 210}, {0, 200, 210}};
    pole.objectToWorld = placement(kTwinGroupA + Eigen::Vector3d(-1.0, -0.1, pole.halfHeight), Eigen::Matrix3d::Identity());
    objects.push_back(pole);
    Object board{.name = "board_b", .kind = ObjectKind::RoundedBox};
    board.halfExtents = {0.3, 0.25, 0.02};
    board.texture = {Texture::Pattern::Stripes, 0.08, 0, 0.0313, {150, 60, 170}, {120, 120, 120}};
    board.objectToWorld = placement(kTwinGroupB + Eigen::Vector3d(1.05, 0.0, 0.35),
                                    rotationAbout(up, degrees(-20)) * rotationAbout(Eigen::Vector3d::UnitY(), degrees(40)));
    objects.push_back(board);

    // Between the groups, so the camera travelling from one to the other always sees more than floor and wall.
    Object crate{.name = "crate", .kind = ObjectKind::RoundedBox};
    crate.halfExtents = {0.35, 0.3, 0.35};
    crate.edgeRadius = 0.02;
    crate.texture = {Texture::Pattern::Checker, 0.12, 2, 0.0171, {120, 80, 40}, {230, 200, 150}};
    crate.objectToWorld = placement({-0.6, 1.1, crate.halfExtents.z()}, rotationAbout(up, degrees(-12)));
    objects.push_back(crate);
    Object ball{.name = "ball", .kind = ObjectKind::Sphere};
    ball.radius = 0.3;
    ball.texture = {Texture::Pattern::Stripes, 0.05, 0, 0.00211, {250, 150, 190}, {40, 40, 40}};
    ball.objectToWorld = placement({0.7, 0.8, 0.9}, Eigen::Matrix3d::Identity());
    objects.push_back(ball);
    Object column{.name = "column", .kind = ObjectKind::Cylinder};
    column.radius = 0.2;
    column.halfHeight = 0.8;
    column.texture = {Texture::Pattern::Checker, 0.07, 2, 0.0093, {230, 210, 40}, {40, 70, 200}};
    column.objectToWorld = placement({0.05, 1.5, column.halfHeight}, Eigen::Matrix3d::Identity());
    objects.push_back(column);

    for (Object& object : objects) object.objectToWorld = toWorld * object.objectToWorld;
    return SyntheticScene(std::move(objects));
}

SyntheticScene SyntheticScene::singleSphere(const Eigen::Vector3d& center, double radius) {
    if (!center.allFinite()) throw Error("singleSphere: centre " + formatVector(center) + " is not finite");
    Object sphere{.name = "sphere", .kind = ObjectKind::Sphere};
    sphere.objectToWorld = placement(center, Eigen::Matrix3d::Identity());
    sphere.radius = radius;
    return SyntheticScene({sphere});
}

SyntheticScene SyntheticScene::slantedPlane(const Eigen::Vector3d& normal, double offset) {
    const double length = normal.norm();
    if (!std::isfinite(length) || length < 1e-12 || !std::isfinite(offset))
        throw Error("slantedPlane: normal " + formatVector(normal) + " and offset " + std::to_string(offset) +
                    " do not define a plane (the normal must be finite and non-zero)");
    const Eigen::Vector3d unitNormal = normal / length;
    // Any rotation taking local z to the normal will do.
    const Eigen::Matrix3d rotation =
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), unitNormal).toRotationMatrix();
    Object plane{.name = "plane", .kind = ObjectKind::HalfSpace};
    plane.objectToWorld = placement(offset * unitNormal, rotation);
    return SyntheticScene({plane});
}

std::string_view pathName(PathKind kind) {
    switch (kind) {
        case PathKind::Orbit: return "orbit";
        case PathKind::Revisit: return "revisit";
        case PathKind::GalleryLoop: return "gallery-loop";
        case PathKind::TwinVisit: return "twin-visit";
    }
    return "unknown";
}

std::vector<Pose> cameraPath(size_t frames, PathKind kind) {
    if (frames == 0) throw Error("cameraPath: frames must be at least 1");
    switch (kind) {
        case PathKind::Orbit: return roomOrbit(frames, 1);
        case PathKind::Revisit: return roomOrbit(frames, kRevisitLaps);
        case PathKind::GalleryLoop: return galleryLoop(frames);
        case PathKind::TwinVisit: return twinVisit(frames);
    }
    throw Error("cameraPath: unknown path kind");
}

}  // namespace vkmesh::synth
