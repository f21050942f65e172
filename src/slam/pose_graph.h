// A pose graph of keyframes (camera-to-world poses) with relative-pose edges, optimised by Ceres (Debian's
// libceres-dev): odometry edges from tracking, loop edges from verified revisits. Each edge's residual is the
// difference between its measured relative pose and the nodes' current one, translation (metres) then rotation
// (twice the error quaternion's vector part, about radians for small angles), whitened by the edge's
// information; loop edges take a Huber loss so that one wrong loop that slipped past verification pulls the
// map with a bounded force. The first node is held fixed (the map's frame).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

#include "core/types.h"

namespace vkmesh::slam {

// Information matrix of a relative pose: 6 x 6, translation (metres) first, then rotation (radians).
using Information = Eigen::Matrix<double, 6, 6>;
// A diagonal information from standard deviations.
Information diagonalInformation(double sigmaMetres, double sigmaRadians);

struct PoseGraphEdge {
    int from = 0, to = 0;
    Pose measured = Pose::Identity();   // inverse(pose(from)) * pose(to) as measured
    Information information = Information::Identity();
    bool loop = false;                  // robust (Huber) loss
};

struct PoseGraphSolve {
    bool converged = false;
    int iterations = 0;
    double initialCost = 0, finalCost = 0;
    double milliseconds = 0;
};

class PoseGraph {
public:
    int addNode(const Pose& cameraToWorld);   // returns its id (0, 1, ...)
    int addEdge(const PoseGraphEdge& edge);   // returns its index; throws Error for an unknown node
    void removeLastEdge();
    size_t nodes() const { return poses_.size(); }
    const std::vector<PoseGraphEdge>& edges() const { return edges_; }
    const Pose& pose(int node) const { return poses_.at(size_t(node)); }
    void setPoses(const std::vector<Pose>& poses) { poses_ = poses; }
    void clear() { poses_.clear(), edges_.clear(); }
    const std::vector<Pose>& poses() const { return poses_; }
    // Moves every node but the first to the least-squares fit of the edges (Levenberg-Marquardt, sparse
    // Cholesky, one thread: the same graph gives the same poses bit for bit).
    PoseGraphSolve optimise(int maxIterations = 50, double huberWhitened = 1.0);
    // An edge's whitened residual's length at the current poses (how many standard deviations it is off).
    double whitenedError(size_t edge) const;

private:
    std::vector<Pose> poses_;
    std::vector<PoseGraphEdge> edges_;
};

}  // namespace vkmesh::slam
