#include "synth/synthetic_scene.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <system_error>
#include <thread>
#include <unordered_set>

namespace vkmesh::synth {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

double degrees(double value) { return value * kPi / 180.0; }

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

// Exact signed distance to an axis-aligned box of half extents `half` centred on the origin.
double boxSdf(const Eigen::Vector3d& q, const Eigen::Vector3d& half) {
    const Eigen::Vector3d d = q.cwiseAbs() - half;
    return d.cwiseMax(0.0).norm() + std::min(d.maxCoeff(), 0.0);
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

// ---------------------------------------------------------------------------------------------------------
// Sphere tracing. Past kHitDistance from a surface the tracer hands over to a bracketing search and a
// bisection, because plain sphere tracing converges only linearly (and very slowly at grazing angles).
constexpr int kMaxSphereTracingSteps = 256;
constexpr double kHitDistance = 1e-4;
// How far past the hand-over point the crossing is searched for. Smaller than the thinnest part of the
// default room (2.5 cm), so the doubling probe steps cannot jump across a part from one side to the other.
constexpr double kCrossingSearchWindow = 0.02;
constexpr double kBisectionTolerance = 1e-7;  // metres along the ray: far below the 0.1 mm depth accuracy
constexpr int kRenderThreads = 2;             // the development and CI machines have two cores

// Kinect v1 noise model (Nguyen, Izadi, Lovell: "Modeling Kinect sensor noise for improved 3D
// reconstruction and tracking", 3DIMPVT 2012), and dropout where structured light loses its pattern.
double axialNoiseSigma(double depth) { return 0.0012 + 0.0019 * (depth - 0.4) * (depth - 0.4); }
constexpr double kGrazingDropStartDegrees = 70.0;
constexpr double kGrazingDropAlwaysDegrees = 80.0;
constexpr double kGrazingDropProbabilityAtAlways = 0.5;
constexpr double kEdgeDropProbability = 0.5;
constexpr double kDiscontinuityRelativeJump = 0.04;

// Points of another object closer than this to a sample are "in contact": such a sample (a standing
// object's bottom, the floor beneath it) cannot be seen from free space and is left out of the ground truth.
constexpr double kContactTolerance = 1e-4;
constexpr double kHalfSpacePatchHalfSize = 4.0;

// SplitMix64: a tiny counter-based generator, seeded per pixel so the noise does not depend on how the rows
// are split between threads.
class PixelRandom {
public:
    PixelRandom(uint32_t seed, uint64_t pixel) : state_((static_cast<uint64_t>(seed) << 32) ^ pixel) {}
    uint64_t next() {
        uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
    double gaussian() {                                                           // Box-Muller
        const double u1 = 1.0 - uniform();                                       // (0, 1]: log is finite
        const double u2 = uniform();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
    }

private:
    uint64_t state_;
};


Rgb shade(const Rgb& c, double exposure, double noiseSigma, PixelRandom* random) {
    Rgb out;
    for (int k = 0; k < 3; ++k) {
        double v = c[k] * exposure;
        if (random) v += noiseSigma * random->gaussian();
        out[k] = static_cast<uint8_t>(std::clamp(std::round(v), 0.0, 255.0));
    }
    return out;
}

void requireFinitePositive(double value, const Object& object, const char* what) {
    if (!std::isfinite(value) || value <= 0)
        throw Error("synthetic object '" + object.name + "' (" + std::string(kindName(object.kind)) + "): " + what +
                    " must be positive and finite, got " + std::to_string(value));
}

void validateObject(const Object& object) {
    if (object.name.empty()) throw Error("synthetic object of kind " + std::string(kindName(object.kind)) + " has no name");
    const Eigen::Matrix3d rotation = object.objectToWorld.linear();
    const double orthonormalError = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!object.objectToWorld.matrix().allFinite() || orthonormalError > 1e-9 || rotation.determinant() < 0)
        throw Error("synthetic object '" + object.name + "': objectToWorld is not a rigid transform (finite, "
                    "orthonormal rotation with determinant +1)");
    const Texture& texture = object.texture;
    if (texture.pattern != Texture::Pattern::Uniform &&
        (!std::isfinite(texture.period) || texture.period <= 0 || !std::isfinite(texture.offset) || texture.axis < 0 ||
         texture.axis > 2))
        throw Error("synthetic object '" + object.name + "': texture period " + std::to_string(texture.period) +
                    " must be positive and finite, offset finite, axis 0..2");
    switch (object.kind) {
        case ObjectKind::HalfSpace: break;
        case ObjectKind::Sphere: requireFinitePositive(object.radius, object, "radius"); break;
        case ObjectKind::Torus:
            requireFinitePositive(object.radius, object, "radius");
            requireFinitePositive(object.tubeRadius, object, "tubeRadius");
            // A self-intersecting (spindle) torus would be sampled twice where it overlaps itself.
            if (object.tubeRadius >= object.radius)
                throw Error("synthetic object '" + object.name + "': tubeRadius " + std::to_string(object.tubeRadius) +
                            " must be smaller than radius " + std::to_string(object.radius));
            break;
        case ObjectKind::RoomInterior:
        case ObjectKind::RoundedBox:
            for (int axis = 0; axis < 3; ++axis) requireFinitePositive(object.halfExtents[axis], object, "halfExtents");
            if (object.kind == ObjectKind::RoundedBox &&
                (!std::isfinite(object.edgeRadius) || object.edgeRadius < 0 ||
                 object.edgeRadius > object.halfExtents.minCoeff()))
                throw Error("synthetic object '" + object.name + "': edgeRadius " + std::to_string(object.edgeRadius) +
                            " must lie in [0, smallest half extent " + std::to_string(object.halfExtents.minCoeff()) + "]");
            break;
        case ObjectKind::Cylinder:
            requireFinitePositive(object.radius, object, "radius");
            requireFinitePositive(object.halfHeight, object, "halfHeight");
            break;
    }
}

// Where the ray o + t d (d unit length) first meets the surface, t in (0, maxT]; nothing when it does not,
// or when the ray starts inside matter (then nothing in front of it is visible).
std::optional<double> intersectRay(const SyntheticScene& scene, const Eigen::Vector3d& origin,
                                   const Eigen::Vector3d& direction, double maxT) {
    auto distanceAt = [&](double t) { return scene.sdf(origin + t * direction); };
    double t = 0, previousT = 0;
    double distance = distanceAt(0);
    if (!(distance > 0)) return std::nullopt;
    int step = 0;
    while (distance >= kHitDistance) {
        if (++step > kMaxSphereTracingSteps) return std::nullopt;  // grazing ray that did not converge
        previousT = t;
        t += distance;
        if (t > maxT) return std::nullopt;
        distance = distanceAt(t);
    }

    // Bracket the crossing: [outside, inside] with sdf(outside) > 0 >= sdf(inside).
    double outside = t, inside = t;
    bool bracketed = false;
    if (distance <= 0) {  // only through rounding: a valid distance bound never overshoots
        outside = previousT;
        bracketed = true;
    } else {
        double offset = 0, probeStep = std::max(distance, kBisectionTolerance);
        while (offset + probeStep <= kCrossingSearchWindow) {
            offset += probeStep;
            const double probeDistance = distanceAt(t + offset);
            if (probeDistance <= 0) {
                inside = t + offset;
                bracketed = true;
                break;
            }
            outside = t + offset;
            probeStep *= 2;
        }
    }
    // The ray only skims the surface (a silhouette) without entering: the closest approach is the hit, less
    // than kHitDistance from the surface.
    if (!bracketed) return t <= maxT ? std::optional<double>(t) : std::nullopt;

    while (inside - outside > kBisectionTolerance) {
        const double middle = 0.5 * (outside + inside);
        if (distanceAt(middle) > 0)
            outside = middle;
        else
            inside = middle;
    }
    const double hit = 0.5 * (outside + inside);
    if (hit > maxT) return std::nullopt;
    return hit;
}

void validatePoseForRendering(const Pose& cameraToWorld) {
    const Eigen::Matrix3d rotation = cameraToWorld.topLeftCorner<3, 3>();
    const double orthonormalError = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!cameraToWorld.allFinite() || orthonormalError > 1e-6 || rotation.determinant() < 0 ||
        (cameraToWorld.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-12) {
        std::ostringstream out;
        out << "renderDepth: cameraToWorld is not a rigid transform:\n" << cameraToWorld;
        throw Error(out.str());
    }
}

// Applies the Kinect-like sensor model to a clean depth image. cosIncidence[i] is |normal . ray| at pixel i.
void applySensorNoise(DepthImage& depth, const std::vector<double>& cosIncidence, uint32_t seed) {
    const DepthImage clean = depth;
    const double cosAlwaysDrop = std::cos(degrees(kGrazingDropAlwaysDegrees));
    auto isDiscontinuity = [&](int x, int y, double z) {
        const std::array<std::array<int, 2>, 4> neighbours{{{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}}};
        for (const auto& [nx, ny] : neighbours) {
            if (nx < 0 || ny < 0 || nx >= clean.width || ny >= clean.height) continue;
            const double neighbourDepth = clean.at(nx, ny);
            if (neighbourDepth <= 0 || std::abs(neighbourDepth - z) > kDiscontinuityRelativeJump * z) return true;
        }
        return false;
    };
    for (int y = 0; y < depth.height; ++y) {
        for (int x = 0; x < depth.width; ++x) {
            const size_t index = static_cast<size_t>(y) * depth.width + x;
            const double z = clean.meters[index];
            if (z <= 0) continue;
            // Always draw the same three numbers per pixel, so one pixel's fate never shifts another's.
            PixelRandom random(seed, index);
            const double grazingDraw = random.uniform();
            const double edgeDraw = random.uniform();
            const double gaussian = random.gaussian();

            const double incidenceDegrees = std::acos(std::clamp(cosIncidence[index], 0.0, 1.0)) * 180.0 / kPi;
            double grazingDropProbability = 0;
            if (cosIncidence[index] < cosAlwaysDrop)
                grazingDropProbability = 1;
            else if (incidenceDegrees > kGrazingDropStartDegrees)
                grazingDropProbability = kGrazingDropProbabilityAtAlways * (incidenceDegrees - kGrazingDropStartDegrees) /
                                         (kGrazingDropAlwaysDegrees - kGrazingDropStartDegrees);
            const bool dropped = grazingDraw < grazingDropProbability ||
                                 (isDiscontinuity(x, y, z) && edgeDraw < kEdgeDropProbability);
            const double noisy = z + axialNoiseSigma(z) * gaussian;
            depth.meters[index] = dropped || noisy <= 0 ? 0.0f : static_cast<float>(noisy);
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Surface sampling, uniform by area, in each primitive's local frame.
class LocalSampler {
public:
    LocalSampler(const Object& object, std::vector<SurfaceSample>& out) : object_(object), out_(out) {}

    void add(const Eigen::Vector3d& localPoint, const Eigen::Vector3d& localNormal) {
        out_.push_back({object_.objectToWorld * localPoint, object_.objectToWorld.linear() * localNormal.normalized()});
    }

    // A rectangle centred at `center` spanned by unit axes u, v with half sizes halfU, halfV, split into
    // cells of about spacing x spacing, one sample at each cell centre.
    void rectangle(const Eigen::Vector3d& center, const Eigen::Vector3d& u, const Eigen::Vector3d& v, double halfU,
                   double halfV, const Eigen::Vector3d& normal, double spacing) {
        if (halfU <= 0 || halfV <= 0) return;
        const int countU = std::max(1, static_cast<int>(std::ceil(2 * halfU / spacing)));
        const int countV = std::max(1, static_cast<int>(std::ceil(2 * halfV / spacing)));
        for (int i = 0; i < countU; ++i)
            for (int j = 0; j < countV; ++j)
                add(center + u * (-halfU + (i + 0.5) * 2 * halfU / countU) + v * (-halfV + (j + 0.5) * 2 * halfV / countV),
                    normal);
    }

private:
    const Object& object_;
    std::vector<SurfaceSample>& out_;
};

// `count` nearly evenly spread unit vectors (Fibonacci lattice): equal area per point on the sphere.
std::vector<Eigen::Vector3d> fibonacciSphere(int count) {
    std::vector<Eigen::Vector3d> directions;
    directions.reserve(count);
    const double goldenAngle = kPi * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < count; ++k) {
        const double z = 1.0 - (2.0 * k + 1.0) / count;
        const double ring = std::sqrt(std::max(0.0, 1.0 - z * z));
        directions.emplace_back(ring * std::cos(goldenAngle * k), ring * std::sin(goldenAngle * k), z);
    }
    return directions;
}

int countForArea(double area, double spacing) {
    return std::max(1, static_cast<int>(std::lround(area / (spacing * spacing))));
}

void sampleRoundedBox(LocalSampler& sampler, const Eigen::Vector3d& half, double edgeRadius, double spacing) {
    const Eigen::Vector3d core = half - Eigen::Vector3d::Constant(edgeRadius);
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const Eigen::Vector3d axisUnit = Eigen::Vector3d::Unit(axis), uUnit = Eigen::Vector3d::Unit(u),
                              vUnit = Eigen::Vector3d::Unit(v);
        for (double side : {-1.0, 1.0}) {
            // Flat face.
            sampler.rectangle(side * half[axis] * axisUnit, uUnit, vUnit, core[u], core[v], side * axisUnit, spacing);
            if (edgeRadius <= 0 || core[axis] <= 0) continue;
            // The quarter cylinders along `axis`, one per (side of u, side of v): `side` plays u's sign here.
            for (double vSide : {-1.0, 1.0}) {
                const Eigen::Vector3d edgeLine = side * core[u] * uUnit + vSide * core[v] * vUnit;
                const int arcCount = std::max(1, static_cast<int>(std::ceil(0.5 * kPi * edgeRadius / spacing)));
                const int lengthCount = std::max(1, static_cast<int>(std::ceil(2 * core[axis] / spacing)));
                for (int a = 0; a < arcCount; ++a) {
                    const double angle = 0.5 * kPi * (a + 0.5) / arcCount;
                    const Eigen::Vector3d normal = std::cos(angle) * side * uUnit + std::sin(angle) * vSide * vUnit;
                    for (int l = 0; l < lengthCount; ++l) {
                        const double along = -core[axis] + (l + 0.5) * 2 * core[axis] / lengthCount;
                        sampler.add(edgeLine + along * axisUnit + edgeRadius * normal, normal);
                    }
                }
            }
        }
    }
    if (edgeRadius <= 0) return;
    // The eight corner octants together make one sphere of radius edgeRadius: spread one lattice over them.
    const double sphereArea = 4 * kPi * edgeRadius * edgeRadius;
    for (const Eigen::Vector3d& direction : fibonacciSphere(countForArea(sphereArea, spacing))) {
        const Eigen::Vector3d corner(std::copysign(core.x(), direction.x()), std::copysign(core.y(), direction.y()),
                                     std::copysign(core.z(), direction.z()));
        sampler.add(corner + edgeRadius * direction, direction);
    }
}

void sampleObject(const Object& object, double spacing, std::vector<SurfaceSample>& out) {
    LocalSampler sampler(object, out);
    switch (object.kind) {
        case ObjectKind::Sphere:
            for (const Eigen::Vector3d& direction :
                 fibonacciSphere(countForArea(4 * kPi * object.radius * object.radius, spacing)))
                sampler.add(object.radius * direction, direction);
            break;
        case ObjectKind::Torus: {
            // Bands around the tube (angle phi); each band's ring is as long as its distance from the axis, so
            // it gets proportionally many samples: uniform by area.
            const int bandCount = std::max(3, static_cast<int>(std::ceil(2 * kPi * object.tubeRadius / spacing)));
            for (int b = 0; b < bandCount; ++b) {
                const double phi = 2 * kPi * (b + 0.5) / bandCount;
                const double ringRadius = object.radius + object.tubeRadius * std::cos(phi);
                const int ringCount = std::max(3, static_cast<int>(std::lround(2 * kPi * ringRadius / spacing)));
                for (int r = 0; r < ringCount; ++r) {
                    const double theta = 2 * kPi * (r + 0.5 * (b % 2)) / ringCount;  // stagger bands
                    const Eigen::Vector3d normal(std::cos(phi) * std::cos(theta), std::cos(phi) * std::sin(theta),
                                                 std::sin(phi));
                    sampler.add(Eigen::Vector3d(ringRadius * std::cos(theta), ringRadius * std::sin(theta),
                                                object.tubeRadius * std::sin(phi)),
                                normal);
                }
            }
            break;
        }
        case ObjectKind::RoundedBox: sampleRoundedBox(sampler, object.halfExtents, object.edgeRadius, spacing); break;
        case ObjectKind::RoomInterior:
            // The six faces of the box, normals pointing into the room (into free space).
            for (int axis = 0; axis < 3; ++axis) {
                const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                for (double side : {-1.0, 1.0})
                    sampler.rectangle(side * object.halfExtents[axis] * Eigen::Vector3d::Unit(axis),
                                      Eigen::Vector3d::Unit(u), Eigen::Vector3d::Unit(v), object.halfExtents[u],
                                      object.halfExtents[v], -side * Eigen::Vector3d::Unit(axis), spacing);
            }
            break;
        case ObjectKind::Cylinder: {
            const double r = object.radius, h = object.halfHeight;
            const int aroundCount = std::max(3, static_cast<int>(std::ceil(2 * kPi * r / spacing)));
            const int heightCount = std::max(1, static_cast<int>(std::ceil(2 * h / spacing)));
            for (int a = 0; a < aroundCount; ++a) {
                const double angle = 2 * kPi * (a + 0.5) / aroundCount;
                const Eigen::Vector3d normal(std::cos(angle), std::sin(angle), 0);
                for (int k = 0; k < heightCount; ++k)
                    sampler.add(r * normal + Eigen::Vector3d(0, 0, -h + (k + 0.5) * 2 * h / heightCount), normal);
            }
            // Caps as concentric rings of equal width, each with samples in proportion to its area.
            const int ringCount = std::max(1, static_cast<int>(std::ceil(r / spacing)));
            const double ringWidth = r / ringCount;
            for (double side : {-1.0, 1.0}) {
                for (int ring = 0; ring < ringCount; ++ring) {
                    const double ringRadius = (ring + 0.5) * ringWidth;
                    const int count = countForArea(2 * kPi * ringRadius * ringWidth, spacing);
                    for (int k = 0; k < count; ++k) {
                        const double angle = 2 * kPi * (k + 0.5 * (ring % 2)) / count;
                        sampler.add(Eigen::Vector3d(ringRadius * std::cos(angle), ringRadius * std::sin(angle), side * h),
                                    Eigen::Vector3d(0, 0, side));
                    }
                }
            }
            break;
        }
        case ObjectKind::HalfSpace: {
            // The plane is infinite: sample the patch around the point nearest the world origin.
            const Eigen::Vector3d originLocal = object.objectToWorld.inverse() * Eigen::Vector3d::Zero();
            sampler.rectangle(Eigen::Vector3d(originLocal.x(), originLocal.y(), 0), Eigen::Vector3d::UnitX(),
                              Eigen::Vector3d::UnitY(), kHalfSpacePatchHalfSize, kHalfSpacePatchHalfSize,
                              Eigen::Vector3d::UnitZ(), spacing);
            break;
        }
    }
}

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
uint32_t frameSeed(uint32_t seed, size_t frame) {
    PixelRandom mixer(seed, 0xF4A3E5000000ull + frame);
    return static_cast<uint32_t>(mixer.next() >> 32);
}

Rgb Texture::at(const Eigen::Vector3d& q) const {
    auto cell = [&](int axisIndex) { return static_cast<long long>(std::floor((q[axisIndex] + offset) / period)); };
    switch (pattern) {
        case Pattern::Uniform: return a;
        case Pattern::Stripes: return (cell(axis) & 1) ? b : a;
        case Pattern::Checker: return ((cell(0) + cell(1) + cell(2)) & 1) ? b : a;
    }
    return a;
}

std::string_view kindName(ObjectKind kind) {
    switch (kind) {
        case ObjectKind::RoomInterior: return "room_interior";
        case ObjectKind::HalfSpace: return "half_space";
        case ObjectKind::Sphere: return "sphere";
        case ObjectKind::Torus: return "torus";
        case ObjectKind::RoundedBox: return "rounded_box";
        case ObjectKind::Cylinder: return "cylinder";
    }
    return "unknown";
}

double Object::sdf(const Eigen::Vector3d& worldPoint) const {
    const Eigen::Vector3d q = objectToWorld.linear().transpose() * (worldPoint - objectToWorld.translation());
    switch (kind) {
        case ObjectKind::RoomInterior: return -boxSdf(q, halfExtents);
        case ObjectKind::HalfSpace: return q.z();
        case ObjectKind::Sphere: return q.norm() - radius;
        case ObjectKind::Torus: {
            const double fromTubeCircle = std::sqrt(q.x() * q.x() + q.y() * q.y()) - radius;
            return std::sqrt(fromTubeCircle * fromTubeCircle + q.z() * q.z()) - tubeRadius;
        }
        case ObjectKind::RoundedBox: return boxSdf(q, halfExtents - Eigen::Vector3d::Constant(edgeRadius)) - edgeRadius;
        case ObjectKind::Cylinder: {
            const double radial = std::sqrt(q.x() * q.x() + q.y() * q.y()) - radius;
            const double axial = std::abs(q.z()) - halfHeight;
            const double outsideRadial = std::max(radial, 0.0), outsideAxial = std::max(axial, 0.0);
            return std::min(std::max(radial, axial), 0.0) +
                   std::sqrt(outsideRadial * outsideRadial + outsideAxial * outsideAxial);
        }
    }
    return kInfinity;
}

double Object::boundingRadius() const {
    switch (kind) {
        case ObjectKind::RoomInterior:
        case ObjectKind::HalfSpace: return kInfinity;
        case ObjectKind::Sphere: return radius;
        case ObjectKind::Torus: return radius + tubeRadius;
        case ObjectKind::RoundedBox: return halfExtents.norm();
        case ObjectKind::Cylinder: return std::sqrt(radius * radius + halfHeight * halfHeight);
    }
    return kInfinity;
}

SyntheticScene::SyntheticScene(std::vector<Object> objects) : objects_(std::move(objects)) {
    if (objects_.empty()) throw Error("a synthetic scene needs at least one object");
    std::unordered_set<std::string> names;
    for (const Object& object : objects_) {
        validateObject(object);
        if (!names.insert(object.name).second) throw Error("synthetic scene: two objects are named '" + object.name + "'");
        boundingRadii_.push_back(object.boundingRadius());
    }
}

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

double SyntheticScene::sdf(const Eigen::Vector3d& p) const {
    double nearest = kInfinity;
    for (size_t i = 0; i < objects_.size(); ++i) {
        // Cheap cull: the distance to an object's bounding sphere is a lower bound of the distance to it.
        if (std::isfinite(boundingRadii_[i]) && (p - objects_[i].center()).norm() - boundingRadii_[i] >= nearest)
            continue;
        nearest = std::min(nearest, objects_[i].sdf(p));
    }
    return nearest;
}

Eigen::Vector3d SyntheticScene::normal(const Eigen::Vector3d& p) const {
    constexpr double h = 1e-6;
    Eigen::Vector3d gradient;
    for (int axis = 0; axis < 3; ++axis) {
        const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(axis);
        gradient[axis] = sdf(p + step) - sdf(p - step);
    }
    const double length = gradient.norm();
    return length > 0 ? Eigen::Vector3d(gradient / length) : Eigen::Vector3d::Zero();
}

Rgb SyntheticScene::color(const Eigen::Vector3d& p) const {
    size_t nearest = 0;
    double best = kInfinity;
    for (size_t i = 0; i < objects_.size(); ++i) {
        const double d = std::abs(objects_[i].sdf(p));
        if (d < best) best = d, nearest = i;
    }
    const Object& object = objects_[nearest];
    return object.texture.at(object.objectToWorld.inverse() * p);
}

const Object& SyntheticScene::object(std::string_view name) const {
    for (const Object& object : objects_)
        if (object.name == name) return object;
    std::string available;
    for (const Object& object : objects_) available += (available.empty() ? "" : ", ") + object.name;
    throw Error("synthetic scene has no object named '" + std::string(name) + "' (it has: " + available + ")");
}

Intrinsics kinectIntrinsics(int width, int height) {
    if (width <= 0 || height <= 0)
        throw Error("kinectIntrinsics: image size " + std::to_string(width) + "x" + std::to_string(height) +
                    " must be positive");
    Intrinsics intrinsics;
    intrinsics.fx = static_cast<float>(525.0 * width / 640.0);
    intrinsics.fy = static_cast<float>(525.0 * height / 480.0);
    // Scale about the image corner in continuous coordinates (pixel centres at integers: corner at -0.5).
    intrinsics.cx = static_cast<float>((319.5 + 0.5) * width / 640.0 - 0.5);
    intrinsics.cy = static_cast<float>((239.5 + 0.5) * height / 480.0 - 0.5);
    intrinsics.width = width;
    intrinsics.height = height;
    return intrinsics;
}

void validateIntrinsics(const Intrinsics& intrinsics) {
    auto fail = [](const std::string& what) { throw Error("bad intrinsics: " + what); };
    if (intrinsics.width <= 0 || intrinsics.height <= 0)
        fail("image size " + std::to_string(intrinsics.width) + "x" + std::to_string(intrinsics.height) +
             " must be positive");
    if (!std::isfinite(intrinsics.fx) || intrinsics.fx == 0) fail("fx = " + std::to_string(intrinsics.fx) + " must be finite and non-zero");
    if (!std::isfinite(intrinsics.fy) || intrinsics.fy == 0) fail("fy = " + std::to_string(intrinsics.fy) + " must be finite and non-zero");
    if (!std::isfinite(intrinsics.cx)) fail("cx = " + std::to_string(intrinsics.cx) + " must be finite");
    if (!std::isfinite(intrinsics.cy)) fail("cy = " + std::to_string(intrinsics.cy) + " must be finite");
}

DepthImage SyntheticScene::renderDepth(const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                       const RenderOptions& options, ColorImage* color) const {
    validateIntrinsics(intrinsics);
    validatePoseForRendering(cameraToWorld);
    if (!std::isfinite(options.maxRange) || options.maxRange <= 0)
        throw Error("renderDepth: maxRange = " + std::to_string(options.maxRange) + " must be positive and finite");
    if (!std::isfinite(options.exposure) || options.exposure < 0 || !std::isfinite(options.colorNoise) || options.colorNoise < 0)
        throw Error("renderDepth: exposure = " + std::to_string(options.exposure) + " and colorNoise = " +
                    std::to_string(options.colorNoise) + " must be finite and >= 0");
    if (color) {
        color->width = intrinsics.width;
        color->height = intrinsics.height;
        color->rgb.assign(static_cast<size_t>(intrinsics.width) * intrinsics.height * 3, 0);
    }

    DepthImage depth;
    depth.width = intrinsics.width;
    depth.height = intrinsics.height;
    const size_t pixelCount = static_cast<size_t>(depth.width) * depth.height;
    depth.meters.assign(pixelCount, 0.0f);
    std::vector<double> cosIncidence(options.noise ? pixelCount : 0, 1.0);

    const Eigen::Matrix3d rotation = cameraToWorld.topLeftCorner<3, 3>();
    const Eigen::Vector3d origin = cameraToWorld.topRightCorner<3, 1>();
    auto renderRows = [&](int firstRow) {
        for (int v = firstRow; v < depth.height; v += kRenderThreads) {
            for (int u = 0; u < depth.width; ++u) {
                const Eigen::Vector3d cameraRay((u - intrinsics.cx) / intrinsics.fx, (v - intrinsics.cy) / intrinsics.fy, 1.0);
                const double rayLengthPerDepth = cameraRay.norm();  // the ray's z component is 1
                const Eigen::Vector3d direction = rotation * (cameraRay / rayLengthPerDepth);
                const std::optional<double> hit =
                    intersectRay(*this, origin, direction, options.maxRange * rayLengthPerDepth);
                if (!hit) continue;
                const size_t index = static_cast<size_t>(v) * depth.width + u;
                depth.meters[index] = static_cast<float>(*hit / rayLengthPerDepth);
                if (options.noise) cosIncidence[index] = std::abs(normal(origin + *hit * direction).dot(direction));
                if (color) {
                    // Its own random stream (seed mixed with a constant), so colour noise leaves depth noise as it was.
                    PixelRandom random(options.seed ^ 0xC0102u, index);
                    const Rgb c = shade(this->color(origin + *hit * direction), options.exposure, options.colorNoise,
                                        options.colorNoise > 0 ? &random : nullptr);
                    std::copy(c.begin(), c.end(), color->rgb.begin() + static_cast<std::ptrdiff_t>(index * 3));
                }
            }
        }
    };
    std::vector<std::thread> workers;
    for (int thread = 1; thread < kRenderThreads; ++thread) workers.emplace_back(renderRows, thread);
    renderRows(0);
    for (std::thread& worker : workers) worker.join();

    if (options.noise) applySensorNoise(depth, cosIncidence, options.seed);
    return depth;
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

std::vector<SurfaceSample> sampleSurface(const SyntheticScene& scene, double spacing) {
    if (!std::isfinite(spacing) || spacing <= 0)
        throw Error("sampleSurface: spacing = " + std::to_string(spacing) + " must be positive and finite");
    const std::vector<Object>& objects = scene.objects();
    std::vector<SurfaceSample> kept;
    std::vector<SurfaceSample> candidates;
    for (size_t i = 0; i < objects.size(); ++i) {
        candidates.clear();
        sampleObject(objects[i], spacing, candidates);
        for (const SurfaceSample& sample : candidates) {
            bool visible = true;
            for (size_t j = 0; j < objects.size() && visible; ++j)
                if (j != i && objects[j].sdf(sample.position) <= kContactTolerance) visible = false;
            if (visible) {
                kept.push_back(sample);
                kept.back().color = objects[i].texture.at(objects[i].objectToWorld.inverse() * sample.position);
            }
        }
    }
    return kept;
}

}  // namespace vkmesh::synth
