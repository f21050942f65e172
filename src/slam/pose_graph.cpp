#include "slam/pose_graph.h"

#include <ceres/ceres.h>

#include <chrono>
#include <string>

namespace vkmesh::slam {
namespace {

// The residual of one relative-pose edge, for Ceres' automatic differentiation.
struct RelativePoseResidual {
    Eigen::Quaterniond measuredRotation;
    Eigen::Vector3d measuredTranslation;
    Eigen::Matrix<double, 6, 6> sqrtInformation;

    template <typename T>
    bool operator()(const T* rotationA, const T* translationA, const T* rotationB, const T* translationB, T* out) const {
        const Eigen::Map<const Eigen::Quaternion<T>> qa(rotationA), qb(rotationB);
        const Eigen::Map<const Eigen::Matrix<T, 3, 1>> ta(translationA), tb(translationB);
        const Eigen::Quaternion<T> qaInverse = qa.conjugate();
        const Eigen::Quaternion<T> relativeRotation = qaInverse * qb;
        const Eigen::Matrix<T, 3, 1> relativeTranslation = qaInverse * (tb - ta);
        const Eigen::Quaternion<T> error = measuredRotation.template cast<T>() * relativeRotation.conjugate();
        Eigen::Matrix<T, 6, 1> r;
        r.template head<3>() = relativeTranslation - measuredTranslation.template cast<T>();
        r.template tail<3>() = T(2.0) * error.vec();
        Eigen::Map<Eigen::Matrix<T, 6, 1>> whitened(out);
        whitened = sqrtInformation.template cast<T>() * r;
        return true;
    }
};

Eigen::Matrix<double, 6, 6> sqrtOf(const Information& information) {
    // Upper Cholesky factor: r' L^T L r = r' I r.
    Eigen::LLT<Information> llt(information);
    if (llt.info() != Eigen::Success) throw Error("pose graph: an edge's information matrix is not positive definite");
    return llt.matrixU();
}

Eigen::Matrix<double, 6, 1> residualOf(const Pose& a, const Pose& b, const PoseGraphEdge& edge) {
    const Eigen::Quaterniond qa(Eigen::Matrix3d(a.block<3, 3>(0, 0))), qb(Eigen::Matrix3d(b.block<3, 3>(0, 0)));
    const Eigen::Quaterniond qm(Eigen::Matrix3d(edge.measured.block<3, 3>(0, 0)));
    const Eigen::Quaterniond relative = qa.conjugate() * qb;
    Eigen::Quaterniond error = qm * relative.conjugate();
    if (error.w() < 0) error.coeffs() = -error.coeffs();
    Eigen::Matrix<double, 6, 1> r;
    r.head<3>() = qa.conjugate() * (b.block<3, 1>(0, 3) - a.block<3, 1>(0, 3)) - edge.measured.block<3, 1>(0, 3);
    r.tail<3>() = 2.0 * error.vec();
    return r;
}

}  // namespace

Information diagonalInformation(double sigmaMetres, double sigmaRadians) {
    Information info = Information::Zero();
    for (int i = 0; i < 3; ++i) info(i, i) = 1.0 / (sigmaMetres * sigmaMetres), info(i + 3, i + 3) = 1.0 / (sigmaRadians * sigmaRadians);
    return info;
}

int PoseGraph::addNode(const Pose& cameraToWorld) {
    poses_.push_back(cameraToWorld);
    return int(poses_.size()) - 1;
}

int PoseGraph::addEdge(const PoseGraphEdge& edge) {
    if (edge.from < 0 || edge.to < 0 || size_t(edge.from) >= poses_.size() || size_t(edge.to) >= poses_.size() || edge.from == edge.to)
        throw Error("pose graph: an edge from node " + std::to_string(edge.from) + " to " + std::to_string(edge.to) + " of " +
                    std::to_string(poses_.size()));
    sqrtOf(edge.information);   // checked now, not in the middle of a solve
    edges_.push_back(edge);
    return int(edges_.size()) - 1;
}

void PoseGraph::removeLastEdge() {
    if (!edges_.empty()) edges_.pop_back();
}

double PoseGraph::whitenedError(size_t e) const {
    const PoseGraphEdge& edge = edges_.at(e);
    return (sqrtOf(edge.information) * residualOf(poses_[size_t(edge.from)], poses_[size_t(edge.to)], edge)).norm();
}

PoseGraphSolve PoseGraph::optimise(int maxIterations, double huberWhitened) {
    const auto t0 = std::chrono::steady_clock::now();
    PoseGraphSolve result;
    if (poses_.size() < 2 || edges_.empty()) return result;
    // Parameter blocks: a unit quaternion (x, y, z, w: Eigen's storage order) and a translation per node.
    std::vector<std::array<double, 4>> rotations(poses_.size());
    std::vector<std::array<double, 3>> translations(poses_.size());
    for (size_t i = 0; i < poses_.size(); ++i) {
        const Eigen::Quaterniond q(Eigen::Matrix3d(poses_[i].block<3, 3>(0, 0)));
        Eigen::Map<Eigen::Quaterniond>(rotations[i].data()) = q.normalized();
        Eigen::Map<Eigen::Vector3d>(translations[i].data()) = poses_[i].block<3, 1>(0, 3);
    }
    ceres::Problem problem;
    for (const PoseGraphEdge& edge : edges_) {
        RelativePoseResidual residual;
        residual.measuredRotation = Eigen::Quaterniond(Eigen::Matrix3d(edge.measured.block<3, 3>(0, 0))).normalized();
        residual.measuredTranslation = edge.measured.block<3, 1>(0, 3);
        residual.sqrtInformation = sqrtOf(edge.information);
        auto* cost = new ceres::AutoDiffCostFunction<RelativePoseResidual, 6, 4, 3, 4, 3>(new RelativePoseResidual(residual));
        ceres::LossFunction* loss = edge.loop && huberWhitened > 0 ? new ceres::HuberLoss(huberWhitened) : nullptr;
        problem.AddResidualBlock(cost, loss, rotations[size_t(edge.from)].data(), translations[size_t(edge.from)].data(),
                                 rotations[size_t(edge.to)].data(), translations[size_t(edge.to)].data());
    }
    for (size_t i = 0; i < poses_.size(); ++i)
        if (problem.HasParameterBlock(rotations[i].data())) problem.SetManifold(rotations[i].data(), new ceres::EigenQuaternionManifold);
    if (!problem.HasParameterBlock(rotations[0].data())) return result;   // the first node has no edge: nothing holds the map
    problem.SetParameterBlockConstant(rotations[0].data());
    problem.SetParameterBlockConstant(translations[0].data());

    ceres::Solver::Options options;
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    options.max_num_iterations = maxIterations;
    options.num_threads = 1;   // deterministic
    options.logging_type = ceres::SILENT;
    options.minimizer_progress_to_stdout = false;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    result.iterations = int(summary.iterations.size());
    result.initialCost = summary.initial_cost;
    result.finalCost = summary.final_cost;
    if (summary.termination_type != ceres::FAILURE) {
        for (size_t i = 1; i < poses_.size(); ++i) {
            if (!problem.HasParameterBlock(rotations[i].data())) continue;
            const Eigen::Quaterniond q = Eigen::Map<const Eigen::Quaterniond>(rotations[i].data()).normalized();
            poses_[i].block<3, 3>(0, 0) = q.toRotationMatrix();
            poses_[i].block<3, 1>(0, 3) = Eigen::Map<const Eigen::Vector3d>(translations[i].data());
        }
    }
    result.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return result;
}

}  // namespace vkmesh::slam
