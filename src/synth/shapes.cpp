// The primitives of a synthetic scene (their textures, signed distances, bounds and checks), their union as
// a SyntheticScene (distance, normal, colour, lookup by name), and the sphere tracer that casts rays into it.
#include "synth/synthetic_scene.h"
#include "synth/synthetic_scene_internal.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <unordered_set>

namespace vkmesh::synth {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Exact signed distance to an axis-aligned box of half extents `half` centred on the origin.
double boxSdf(const Eigen::Vector3d& q, const Eigen::Vector3d& half) {
    const Eigen::Vector3d d = q.cwiseAbs() - half;
    return d.cwiseMax(0.0).norm() + std::min(d.maxCoeff(), 0.0);
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

}  // namespace

// ---------------------------------------------------------------------------------------------------------
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
    buildNearestGrid();
}

// Why a cell's list gives the exact minimum: every object's sdf is exact, so it changes by at most the distance
// moved (1-Lipschitz). With c a cell's centre and h its half-diagonal, every point p of the cell has
// sdf_j(p) <= sdf_j(c) + h for each j, so the scene's sdf(p) <= U = min_j sdf_j(c) + h; and an object with
// sdf_i(c) - h > U has sdf_i(p) > U >= sdf(p) everywhere in the cell: it is never the minimum there, and the
// minimum over the others is the same number. kLipschitzSlack covers rounding (and a point that floor() puts
// in the next cell by an ulp).
void SyntheticScene::buildNearestGrid() {
    constexpr size_t kMinObjects = 4;          // below this, the list would save little
    constexpr double kCellsOnLongestAxis = 64;
    constexpr double kLipschitzSlack = 1e-6;   // metres
    if (objects_.size() < kMinObjects || objects_.size() > std::numeric_limits<uint16_t>::max()) return;
    Eigen::AlignedBox3d bounds;
    for (size_t i = 0; i < objects_.size(); ++i) {
        const Object& object = objects_[i];
        if (std::isfinite(boundingRadii_[i])) {
            bounds.extend(object.center() - Eigen::Vector3d::Constant(boundingRadii_[i]));
            bounds.extend(object.center() + Eigen::Vector3d::Constant(boundingRadii_[i]));
        } else if (object.kind == ObjectKind::RoomInterior) {  // where cameras are: inside a room
            for (int corner = 0; corner < 8; ++corner) {
                const Eigen::Vector3d sign((corner & 1) ? 1 : -1, (corner & 2) ? 1 : -1, (corner & 4) ? 1 : -1);
                bounds.extend(object.objectToWorld * Eigen::Vector3d(sign.cwiseProduct(object.halfExtents)));
            }
        }
    }
    if (bounds.isEmpty()) return;
    NearestGrid grid;
    grid.origin = bounds.min();
    grid.cellSize = bounds.sizes().maxCoeff() / kCellsOnLongestAxis;
    if (!(grid.cellSize > 0)) return;
    for (int axis = 0; axis < 3; ++axis)
        grid.cells[axis] = std::max(1, static_cast<int>(std::ceil(bounds.sizes()[axis] / grid.cellSize)));
    const double halfDiagonal = 0.5 * std::sqrt(3.0) * grid.cellSize;
    std::vector<double> atCentre(objects_.size());
    grid.firstOfCell.reserve(static_cast<size_t>(grid.cells.prod()) + 1);
    grid.firstOfCell.push_back(0);
    for (int z = 0; z < grid.cells.z(); ++z)
        for (int y = 0; y < grid.cells.y(); ++y)
            for (int x = 0; x < grid.cells.x(); ++x) {
                const Eigen::Vector3d centre = grid.origin + (Eigen::Vector3d(x, y, z) + Eigen::Vector3d::Constant(0.5)) * grid.cellSize;
                double upperBound = kInfinity;
                for (size_t i = 0; i < objects_.size(); ++i) {
                    atCentre[i] = objects_[i].sdf(centre);
                    upperBound = std::min(upperBound, atCentre[i] + halfDiagonal);
                }
                for (size_t i = 0; i < objects_.size(); ++i)
                    if (atCentre[i] - halfDiagonal <= upperBound + kLipschitzSlack) grid.objects.push_back(static_cast<uint16_t>(i));
                grid.firstOfCell.push_back(static_cast<uint32_t>(grid.objects.size()));
            }
    nearestGrid_ = std::move(grid);
}

double SyntheticScene::sdf(const Eigen::Vector3d& p) const {
    double nearest = kInfinity;
    auto take = [&](size_t i) {
        // Cheap cull: the distance to an object's bounding sphere is a lower bound of the distance to it.
        if (std::isfinite(boundingRadii_[i]) && (p - objects_[i].center()).norm() - boundingRadii_[i] >= nearest) return;
        nearest = std::min(nearest, objects_[i].sdf(p));
    };
    const NearestGrid& grid = nearestGrid_;
    if (!grid.firstOfCell.empty()) {
        const Eigen::Vector3d at = (p - grid.origin) / grid.cellSize;
        if (at.x() >= 0 && at.y() >= 0 && at.z() >= 0 && at.x() < grid.cells.x() && at.y() < grid.cells.y() && at.z() < grid.cells.z()) {
            const size_t cell = (static_cast<size_t>(at.z()) * grid.cells.y() + static_cast<size_t>(at.y())) * grid.cells.x() +
                                static_cast<size_t>(at.x());
            for (uint32_t k = grid.firstOfCell[cell]; k < grid.firstOfCell[cell + 1]; ++k) take(grid.objects[k]);
            return nearest;
        }
    }
    for (size_t i = 0; i < objects_.size(); ++i) take(i);
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

namespace {

// ---------------------------------------------------------------------------------------------------------
// Sphere tracing. Past kHitDistance from a surface the tracer hands over to a bracketing search and a
// bisection, because plain sphere tracing converges only linearly (and very slowly at grazing angles).
constexpr int kMaxSphereTracingSteps = 256;
constexpr double kHitDistance = 1e-4;
// How far past the hand-over point the crossing is searched for. Smaller than the thinnest part of the
// default room (2.5 cm), so the doubling probe steps cannot jump across a part from one side to the other.
constexpr double kCrossingSearchWindow = 0.02;
constexpr double kBisectionTolerance = 1e-7;  // metres along the ray: far below the 0.1 mm depth accuracy

}  // namespace

namespace detail {

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

}  // namespace detail

}  // namespace vkmesh::synth
