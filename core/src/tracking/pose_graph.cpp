#include "dynamap/core/tracking/pose_graph.hpp"

#include <algorithm>
#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>

namespace dynamap {
namespace {

/// Whitened error of T_from_to_measured^-1 * (T_W_from^-1 * T_W_to): translation (3) and twice
/// the vector part of the rotation error quaternion (3), as in Ceres' pose_graph_3d example.
struct RelativePoseResidual {
  RelativePoseResidual(const Eigen::Isometry3d& T_from_to, double sigma_m, double sigma_rad)
      : q_meas(T_from_to.rotation()),
        t_meas(T_from_to.translation()),
        w_t(1.0 / sigma_m),
        w_r(1.0 / sigma_rad) {}

  template <typename T>
  bool operator()(const T* q_a_ptr, const T* t_a_ptr, const T* q_b_ptr, const T* t_b_ptr,
                  T* r_ptr) const {
    Eigen::Map<const Eigen::Quaternion<T>> q_a(q_a_ptr), q_b(q_b_ptr);
    Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_a(t_a_ptr), t_b(t_b_ptr);
    const Eigen::Quaternion<T> q_a_inv = q_a.conjugate();
    const Eigen::Quaternion<T> q_ab = q_a_inv * q_b;
    const Eigen::Matrix<T, 3, 1> t_ab = q_a_inv * (t_b - t_a);
    const Eigen::Quaternion<T> dq = q_meas.template cast<T>() * q_ab.conjugate();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(r_ptr);
    r.template head<3>() = (t_ab - t_meas.template cast<T>()) * T(w_t);
    r.template tail<3>() = T(2.0) * dq.vec() * T(w_r);
    return true;
  }

  Eigen::Quaterniond q_meas;
  Eigen::Vector3d t_meas;
  double w_t, w_r;
};

}  // namespace

int PoseGraph::addNode(const Eigen::Isometry3d& T_W_C, bool fixed) {
  Node n{};
  const Eigen::Quaterniond q(T_W_C.rotation());
  n.q[0] = q.x(), n.q[1] = q.y(), n.q[2] = q.z(), n.q[3] = q.w();
  for (int i = 0; i < 3; ++i) n.t[i] = T_W_C.translation()[i];
  n.fixed = fixed;
  nodes_.push_back(n);
  return static_cast<int>(nodes_.size()) - 1;
}

void PoseGraph::addEdge(const PoseGraphEdge& edge) {
  if (edge.from < 0 || edge.to < 0 || edge.from >= size() || edge.to >= size() ||
      edge.from == edge.to || !(edge.sigma_m > 0.0) || !(edge.sigma_rad > 0.0)) {
    throw std::invalid_argument("PoseGraph::addEdge: bad node index or sigma");
  }
  edges_.push_back(edge);
}

bool PoseGraph::optimize(const PoseGraphOptions& options) {
  if (nodes_.empty()) return false;
  // A robust loss far from the solution (a loop edge tens of sigmas off before the correction)
  // would hardly pull: least squares first, then the robust loss from there.
  const bool any_robust =
      std::any_of(edges_.begin(), edges_.end(), [](const PoseGraphEdge& e) { return e.robust; });
  std::vector<Node> work = nodes_;
  if (!solve(options, /*robust=*/false, work)) return false;
  if (any_robust && !solve(options, /*robust=*/true, work)) return false;
  nodes_ = work;
  return true;
}

bool PoseGraph::solve(const PoseGraphOptions& options, bool robust, std::vector<Node>& work) {
  ceres::Problem problem;
  ceres::LossFunction* cauchy = robust ? new ceres::CauchyLoss(options.robust_scale) : nullptr;
  for (const PoseGraphEdge& e : edges_) {
    Node& a = work[static_cast<std::size_t>(e.from)];
    Node& b = work[static_cast<std::size_t>(e.to)];
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseResidual, 6, 4, 3, 4, 3>(
        new RelativePoseResidual(e.T_from_to, e.sigma_m, e.sigma_rad));
    problem.AddResidualBlock(cost, e.robust ? cauchy : nullptr, a.q, a.t, b.q, b.t);
  }
  const bool cauchy_used = robust && std::any_of(edges_.begin(), edges_.end(),
                                                 [](const PoseGraphEdge& e) { return e.robust; });
  if (!cauchy_used) delete cauchy;  // the problem owns it only once a residual uses it
  for (Node& n : work) {
    if (!problem.HasParameterBlock(n.q)) continue;
    problem.SetManifold(n.q, new ceres::EigenQuaternionManifold);
    if (n.fixed) {
      problem.SetParameterBlockConstant(n.q);
      problem.SetParameterBlockConstant(n.t);
    }
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  final_cost_ = summary.final_cost;
  return summary.IsSolutionUsable();
}

Eigen::Isometry3d PoseGraph::pose(int node) const {
  const Node& n = nodes_.at(static_cast<std::size_t>(node));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(n.q[3], n.q[0], n.q[1], n.q[2]).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(n.t[0], n.t[1], n.t[2]);
  return T;
}

}  // namespace dynamap
