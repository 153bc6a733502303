#pragma once

#include <vector>

#include <Eigen/Geometry>

namespace dynamap {

/// A relative-pose measurement between two nodes: T_Cfrom_Cto, with isotropic standard
/// deviations of its translation (metres) and rotation (radians).
struct PoseGraphEdge {
  int from = 0;
  int to = 0;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();
  double sigma_m = 0.01;
  double sigma_rad = 0.01;
  bool robust = false;  ///< Cauchy loss in a second pass (loop edges: a wrong one pulls less)
};

struct PoseGraphOptions {
  int max_iterations = 100;
  double robust_scale = 3.0;  ///< Cauchy scale on the whitened residual (sigmas)
};

/// SE(3) pose graph (Ceres): nodes are camera -> world poses T_W_C (unit quaternion + position),
/// edges relative poses; fixed nodes (at least the first keyframe) hold the gauge.
/// optimize(): least squares, then (if an edge is robust) again with the Cauchy loss from there.
/// Not thread-safe: build, optimize and read on one thread.
class PoseGraph {
 public:
  int addNode(const Eigen::Isometry3d& T_W_C, bool fixed);
  void addEdge(const PoseGraphEdge& edge);
  /// Returns false when Ceres reports no usable solution (poses are then left as they were).
  bool optimize(const PoseGraphOptions& options = {});
  Eigen::Isometry3d pose(int node) const;
  int size() const { return static_cast<int>(nodes_.size()); }
  double finalCost() const { return final_cost_; }

 private:
  struct Node {
    double q[4];  ///< x, y, z, w (Eigen's storage order)
    double t[3];
    bool fixed;
  };
  bool solve(const PoseGraphOptions& options, bool robust, std::vector<Node>& work);

  std::vector<Node> nodes_;
  std::vector<PoseGraphEdge> edges_;
  double final_cost_ = 0.0;
};

}  // namespace dynamap
