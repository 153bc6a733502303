#include "dynamap/core/tracking/reference_blend.hpp"

namespace dynamap {
namespace {

/// The rigid motion `share` (0..1) of the way from identity to `T`.
Eigen::Isometry3d partOf(const Eigen::Isometry3d& T, double share) {
  const Eigen::Quaterniond q(T.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond::Identity().slerp(share, q).toRotationMatrix();
  out.translation() = share * T.translation();
  return out;
}

/// Whether frame i begins a new span of one reference keyframe.
bool switchesReference(const std::vector<ReferencedFrame>& f, std::size_t i) {
  return f[i].has_ref && i > 0 && f[i - 1].has_ref && f[i].ref_kf != f[i - 1].ref_kf;
}

}  // namespace

std::vector<Eigen::Isometry3d> blendReferenceSwitches(const std::vector<ReferencedFrame>& frames) {
  const std::size_t n = frames.size();
  std::vector<Eigen::Isometry3d> out(n);
  std::size_t begin = 0;  // first frame of the current span
  for (std::size_t i = 0; i < n; ++i) {
    const ReferencedFrame& f = frames[i];
    out[i] = f.has_ref ? f.correction * f.T_W_C_tracked : f.T_W_C_tracked;
    if (!f.has_ref) begin = i + 1;
    if (!switchesReference(frames, i)) continue;
    // Frames [begin, i) drift away from frame i's correction: frame k takes the share
    // (t_k - t_begin) / (t_i - t_begin) of the jump on top of its own.
    const Eigen::Isometry3d jump = f.correction * frames[i - 1].correction.inverse();
    const double span_s = f.timestamp_s - frames[begin].timestamp_s;
    if (span_s > 0.0) {
      for (std::size_t k = begin; k < i; ++k) {
        const double share = (frames[k].timestamp_s - frames[begin].timestamp_s) / span_s;
        out[k] = partOf(jump, share) * out[k];
      }
    }
    begin = i;
  }
  return out;
}

}  // namespace dynamap
