// Ground truth of a synthetic scene: every object's surface sampled uniformly by area (sampleSurface), with
// the scene's colour, leaving out what touches or lies inside another object.
#include "synth/synthetic_scene.h"
#include "synth/synthetic_scene_internal.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace vkmesh::synth {

using detail::kPi;

namespace {

// Points of another object closer than this to a sample are "in contact": such a sample (a standing
// object's bottom, the floor beneath it) cannot be seen from free space and is left out of the ground truth.
constexpr double kContactTolerance = 1e-4;
constexpr double kHalfSpacePatchHalfSize = 4.0;

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

}  // namespace

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
