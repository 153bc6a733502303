#include "dynamap/core/tracking/local_ba.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "dynamap/core/tracking/rgbd_residual.hpp"

namespace dynamap {
namespace {
constexpr std::size_t kDenseSchurMaxPoses = 100;

/// TrackerConfig::ba_acceleration_sigma_mps2: an acceleration prior on every three keyframes in
/// a row in time, each close after the one before (a saved map's keyframes take no part).
void addAccelerationPriors(const TrackerConfig& config, const BaWindow& window,
                           std::vector<std::array<double, 6>>& poses, ceres::Problem& problem,
                           ceres::LossFunction* loss) {
  const std::vector<double>& t = window.timestamps_s;
  if (config.ba_acceleration_sigma_mps2 <= 0.0 || t.size() != poses.size()) return;
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (std::isfinite(t[k])) order.push_back(k);
  }
  std::sort(order.begin(), order.end(), [&t](std::size_t a, std::size_t b) { return t[a] < t[b]; });
  const double max_gap = config.ba_acceleration_max_gap_s;
  for (std::size_t i = 2; i < order.size(); ++i) {
    const std::size_t a = order[i - 2], b = order[i - 1], c = order[i];
    const double dt_ab = t[b] - t[a], dt_bc = t[c] - t[b];
    if (dt_ab <= 0.0 || dt_bc <= 0.0 || dt_ab > max_gap || dt_bc > max_gap) continue;
    if (window.fixed[a] && window.fixed[b] && window.fixed[c]) continue;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<AccelerationResidual, 3, 6, 6, 6>(
            new AccelerationResidual(dt_ab, dt_bc, config.ba_acceleration_sigma_mps2)),
        loss, poses[a].data(), poses[b].data(), poses[c].data());
  }
}
}  // namespace

bool solveBundleAdjustment(const PinholeCamera& camera, const TrackerConfig& config,
                           BaWindow& window) {
  if (window.observations.empty() || window.landmark_ids.empty()) return false;
  std::vector<std::array<double, 6>> poses(window.poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) toPoseBlock(window.poses[k], poses[k].data());
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::HuberLoss loss(config.robust_loss_sigma);
  for (const auto& o : window.observations) {
    const double inv_sigma_z = config.use_depth_residual && o.depth_m > 0.0
                                   ? 1.0 / depthSigma(config.depth_sigma_coeff, o.depth_m)
                                   : 0.0;
    const RgbdResidual residual(camera, o.px, config.use_depth_residual ? o.depth_m : 0.0,
                                1.0 / config.pixel_sigma_px, inv_sigma_z);
    ceres::CostFunction* cost = nullptr;
    if (o.attached < 0) {
      cost = new ceres::AutoDiffCostFunction<RgbdResidual, 3, 6, 3>(new RgbdResidual(residual));
    } else {
      cost =
          new ceres::AutoDiffCostFunction<RgbdAttachedResidual, 3, 6, 3>(new RgbdAttachedResidual(
              residual, window.attached[static_cast<std::size_t>(o.attached)]));
    }
    problem.AddResidualBlock(cost, &loss, poses[static_cast<std::size_t>(o.keyframe)].data(),
                             window.points[static_cast<std::size_t>(o.landmark)].data());
  }
  addAccelerationPriors(config, window, poses, problem, &loss);
  bool any_free = false;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    if (window.fixed[k]) {
      problem.SetParameterBlockConstant(poses[k].data());
    } else {
      any_free = true;
    }
  }
  if (!any_free) return false;
  ceres::Solver::Options options;
  // Dense Schur is the faster up to ~100 poses (62 keyframes of the crowd sequence at finish:
  // 146 ms dense, 196-276 ms sparse); its cost grows with the cube of the poses, sparse's less.
  options.linear_solver_type =
      window.poses.size() > kDenseSchurMaxPoses ? ceres::SPARSE_SCHUR : ceres::DENSE_SCHUR;
  options.max_num_iterations = config.ba_max_iterations;
  options.logging_type = ceres::SILENT;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable()) return false;
  for (std::size_t k = 0; k < poses.size(); ++k) window.poses[k] = fromPoseBlock(poses[k].data());
  return true;
}

LocalBundleAdjuster::LocalBundleAdjuster(const PinholeCamera& camera, const TrackerConfig& config,
                                         LocalMap& map, TimingRecorder* timings)
    : camera_(camera), config_(config), map_(map), timings_(timings) {}

LocalBundleAdjuster::~LocalBundleAdjuster() { stop(); }

void LocalBundleAdjuster::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (thread_.joinable() || stop_) return;
  thread_ = std::thread([this] { loop(); });
}

bool LocalBundleAdjuster::nextRunIsGlobal() {
  ++requests_;
  const int every = config_.ba_global_every_keyframes;
  const bool global = every > 0 && requests_ % every == 0;
  since_global_ = global ? 0 : since_global_ + 1;
  return global;
}

void LocalBundleAdjuster::requestRun() {
  bool global = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    global = nextRunIsGlobal();
  }
  // ba_lockstep: the window is taken now, on the tracker's thread, so that what the BA sees
  // (landmarks marked bad per frame included) does not depend on when its thread wakes up.
  std::optional<BaWindow> job;
  if (config_.ba_lockstep) job = snapshot(global);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = true;
    pending_global_ = global;
    job_ = std::move(job);
  }
  wake_.notify_all();
}

int LocalBundleAdjuster::runsSinceGlobal() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return since_global_;
}

void LocalBundleAdjuster::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

BaWindow LocalBundleAdjuster::windowOf(int keyframes) const {
  return map_.snapshotWindow(keyframes, config_.ba_fixed_keyframes, config_.ba_fixed_covisible,
                             config_.ba_covisible_min_age_s);
}

BaWindow LocalBundleAdjuster::snapshot(bool global) const {
  BaWindow w = windowOf(global ? static_cast<int>(map_.keyframeCount()) : config_.ba_window);
  w.global = global;
  return w;
}

bool LocalBundleAdjuster::solve(BaWindow& window) {
  ScopedStageTimer timer(timings_, window.global ? "ba_global" : "ba");
  return solveBundleAdjustment(camera_, config_, window);
}

void LocalBundleAdjuster::write(const BaWindow& solved) {
  std::vector<PoseUpdate> moved = map_.apply(solved);
  if (moved.empty()) return;  // nothing free, or taken before a loop correction
  if (listener_) listener_(moved, solved.generation);
  queueUpdates(moved);
}

void LocalBundleAdjuster::queueUpdates(const std::vector<PoseUpdate>& moved) {
  std::lock_guard<std::mutex> lock(updates_mutex_);
  updates_.insert(updates_.end(), moved.begin(), moved.end());
}

void LocalBundleAdjuster::runOnce(int window_keyframes, int max_iterations) {
  BaWindow window = window_keyframes > 0 ? windowOf(window_keyframes) : snapshot(false);
  TrackerConfig config = config_;
  if (max_iterations > 0) config.ba_max_iterations = max_iterations;
  ScopedStageTimer timer(timings_, "ba_final");
  if (solveBundleAdjustment(camera_, config, window)) write(window);
}

void LocalBundleAdjuster::applyFinished() {
  std::optional<BaWindow> solved;
  {
    ScopedStageTimer wait(timings_, "ba_wait");  // the tracker waiting for the last solve
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait(lock, [this] { return (!pending_ && !running_) || !thread_.joinable() || stop_; });
    solved.swap(solved_);
  }
  if (solved) write(*solved);
}

std::vector<PoseUpdate> LocalBundleAdjuster::takeUpdates() {
  std::lock_guard<std::mutex> lock(updates_mutex_);
  std::vector<PoseUpdate> out;
  out.swap(updates_);
  return out;
}

void LocalBundleAdjuster::loop() {
  std::optional<BaWindow> job;
  for (;;) {
    bool global = false;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return pending_ || stop_; });
      if (stop_) return;
      pending_ = false;
      running_ = true;
      global = pending_global_;
      job.swap(job_);
    }
    if (!job) job = snapshot(global);  // not lockstep: the map as it is now
    const bool solved = solve(*job);
    if (solved && !config_.ba_lockstep) write(*job);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (solved && config_.ba_lockstep) solved_ = std::move(job);
      job.reset();
      running_ = false;
    }
    wake_.notify_all();
  }
}

}  // namespace dynamap
