#include "dynamap/core/tracking/pose_optimizer.hpp"

#include <cmath>
#include <cstdint>
#include <memory>

#include <ceres/rotation.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "dynamap/core/tracking/rgbd_residual.hpp"

namespace dynamap {

constexpr std::uint64_t kPnpSeed = 0x9e3779b97f4a7c15ULL;  ///< PnP RANSAC's sampling seed
namespace {

constexpr double kChi2Mono = 5.991;    // 95 %, 2 dof
constexpr double kChi2Stereo = 7.815;  // 95 %, 3 dof

RgbdResidual makeResidual(const PinholeCamera& camera, const TrackerConfig& config,
                          const PoseCorrespondence& c) {
  const double inv_sigma_z = config.use_depth_residual && c.depth_m > 0.0
                                 ? 1.0 / depthSigma(config.depth_sigma_coeff, c.depth_m)
                                 : 0.0;
  return RgbdResidual(camera, c.px, config.use_depth_residual ? c.depth_m : 0.0,
                      1.0 / (config.pixel_sigma_px * c.sigma_scale), inv_sigma_z);
}

/// Holds a pose block near a predicted one: rotation vector difference / sigma_rad and camera
/// centre difference / sigma_m (the centre, not T_C_W's translation, which a small rotation
/// far from the world origin moves a lot).
struct MotionPriorResidual {
  MotionPriorResidual(const double* predicted, double inv_sigma_rad, double inv_sigma_m)
      : inv_sigma_rad_(inv_sigma_rad), inv_sigma_m_(inv_sigma_m) {
    for (int i = 0; i < 6; ++i) pred_[i] = predicted[i];
    poseBlockCentre(pred_, centre_);
  }
  template <typename T>
  bool operator()(const T* p, T* r) const {
    T c[3];
    poseBlockCentre(p, c);
    for (int i = 0; i < 3; ++i) {
      r[i] = (p[i] - T(pred_[i])) * T(inv_sigma_rad_);
      r[3 + i] = (c[i] - T(centre_[i])) * T(inv_sigma_m_);
    }
    return true;
  }
  double pred_[6];
  double centre_[3];
  double inv_sigma_rad_, inv_sigma_m_;
};

}  // namespace

PoseOptimizer::PoseOptimizer(const PinholeCamera& camera, const TrackerConfig& config)
    : camera_(camera), config_(config) {}

bool PoseOptimizer::ransac(const std::vector<PoseCorrespondence>& corr, Eigen::Isometry3d& T_W_C,
                           std::vector<std::uint8_t>& inlier, bool use_guess,
                           int iterations) const {
  inlier.assign(corr.size(), 0);
  if (corr.size() < 6) return false;
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  object.reserve(corr.size());
  image.reserve(corr.size());
  for (const auto& c : corr) {
    object.emplace_back(static_cast<float>(c.p_W.x()), static_cast<float>(c.p_W.y()),
                        static_cast<float>(c.p_W.z()));
    image.emplace_back(static_cast<float>(c.px.x()), static_cast<float>(c.px.y()));
  }
  const cv::Matx33d K(camera_.fx, 0, camera_.cx, 0, camera_.fy, camera_.cy, 0, 0, 1);
  const Eigen::Isometry3d T_C_W = T_W_C.inverse();
  cv::Mat R, rvec, tvec;
  cv::eigen2cv(Eigen::Matrix3d(T_C_W.rotation()), R);
  cv::Rodrigues(R, rvec);
  cv::eigen2cv(Eigen::Vector3d(T_C_W.translation()), tvec);
  std::vector<int> idx;
  // solvePnPRansac draws from the thread's cv::theRNG(): seeded per call (and restored), a pose
  // depends on its inputs only, not on what else ran on this thread before (two Systems
  // interleaved on one thread give the same poses as each alone).
  const cv::RNG saved = cv::theRNG();
  cv::theRNG() = cv::RNG(kPnpSeed);
  const bool ok = cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, use_guess,
                                     iterations > 0 ? iterations : config_.pnp_ransac_iterations,
                                     static_cast<float>(config_.pnp_reprojection_px), 0.99, idx,
                                     use_guess ? cv::SOLVEPNP_ITERATIVE : cv::SOLVEPNP_AP3P);
  cv::theRNG() = saved;
  if (!ok || static_cast<int>(idx.size()) < 4) return false;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d Re;
  Eigen::Vector3d te;
  cv::cv2eigen(R, Re);
  cv::cv2eigen(tvec, te);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Re;
  T.translation() = te;
  // OpenCV refines the final model on its inliers, which can (rarely) jump to a wrong minimum:
  // keep the result only if it still explains most of RANSAC's inliers.
  const double th2 = config_.pnp_reprojection_px * config_.pnp_reprojection_px;
  int count = 0;
  for (std::size_t i = 0; i < corr.size(); ++i) {
    const Eigen::Vector3d p_C = T * corr[i].p_W;
    if (p_C.z() <= 0.0) continue;
    if ((camera_.project(p_C) - corr[i].px).squaredNorm() > th2) continue;
    inlier[i] = 1;
    ++count;
  }
  if (2 * count < static_cast<int>(idx.size())) {
    inlier.assign(corr.size(), 0);
    return false;
  }
  T_W_C = T.inverse();
  return true;
}

int PoseOptimizer::refine(const std::vector<PoseCorrespondence>& corr, Eigen::Isometry3d& T_W_C,
                          std::vector<std::uint8_t>& inlier,
                          const Eigen::Isometry3d* predicted) const {
  double pose[6], pred[6];
  toPoseBlock(T_W_C, pose);
  const bool use_prior = predicted != nullptr && config_.motion_prior_sigma_m > 0.0 &&
                         config_.motion_prior_sigma_deg > 0.0;
  if (use_prior) toPoseBlock(*predicted, pred);
  ceres::HuberLoss loss(config_.robust_loss_sigma);
  int count = 0;
  for (int round = 0; round < 2; ++round) {
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    int used = 0;
    for (std::size_t i = 0; i < corr.size(); ++i) {
      if (!inlier[i]) continue;
      auto* cost = new ceres::AutoDiffCostFunction<RgbdPoseOnlyResidual, 3, 6>(
          new RgbdPoseOnlyResidual(makeResidual(camera_, config_, corr[i]), corr[i].p_W));
      problem.AddResidualBlock(cost, &loss, pose);
      ++used;
    }
    if (use_prior && used > 0) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<MotionPriorResidual, 6, 6>(
              new MotionPriorResidual(pred, 1.0 / (config_.motion_prior_sigma_deg * M_PI / 180.0),
                                      1.0 / config_.motion_prior_sigma_m)),
          nullptr, pose);
    }
    if (used < 4) break;
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_QR;
    options.max_num_iterations = config_.refine_iterations;
    options.logging_type = ceres::SILENT;
    options.num_threads = 1;
    ceres::Solver::Summary summary;
    if (config_.refine_iterations > 0) ceres::Solve(options, &problem, &summary);
    count = 0;
    for (std::size_t i = 0; i < corr.size(); ++i) {
      const RgbdResidual r = makeResidual(camera_, config_, corr[i]);
      double res[3];
      r(pose, corr[i].p_W.data(), res);
      const double chi2 = res[0] * res[0] + res[1] * res[1] + res[2] * res[2];
      const bool ok = chi2 < (r.w_z > 0.0 ? kChi2Stereo : kChi2Mono);
      inlier[i] = ok ? 1 : 0;
      count += ok ? 1 : 0;
    }
  }
  T_W_C = fromPoseBlock(pose);
  return count;
}

PoseEstimate PoseOptimizer::estimate(const std::vector<PoseCorrespondence>& corr,
                                     const Eigen::Isometry3d& T_W_C_guess,
                                     TimingRecorder* timings) const {
  PoseEstimate est;
  est.T_W_C = T_W_C_guess;
  {
    ScopedStageTimer timer(timings, "pnp");
    const bool rok = ransac(corr, est.T_W_C, est.inlier);
    if (!rok) {
      // No RANSAC model: start the robust refinement from the prediction with every match.
      est.T_W_C = T_W_C_guess;
      est.inlier.assign(corr.size(), 1);
    }
  }
  ScopedStageTimer timer(timings, "pose_refine");
  est.inliers = refine(corr, est.T_W_C, est.inlier, &T_W_C_guess);
  est.ok = est.inliers >= config_.min_inliers;
  return est;
}

}  // namespace dynamap
