#include "dynamap/mapping/held_revision.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "dynamap/mapping/flat_index.hpp"
#include "dynamap/mapping/in_two.hpp"
#include "visibility_table.hpp"

namespace dynamap {
namespace {

/// The keyframes that saw a voxel confirmed static, and those that saw it masked for motion
/// (keyframes come in order, so each is counted once).
constexpr int kListed = 8;
struct VoxelVotes {
  std::array<int, kListed> confirmers{};
  int listed = 0;
  int confirmed = 0;
  int moved = 0;
  int last_confirmer = -1;
  int last_mover = -1;
  void confirm(int k) {
    if (k == last_confirmer) return;
    last_confirmer = k;
    ++confirmed;
    if (listed < kListed) confirmers[static_cast<std::size_t>(listed++)] = k;
  }
  void move(int k) {
    if (k == last_mover) return;
    last_mover = k;
    ++moved;
  }
  int confirmedByOthers(int k) const {
    for (int i = 0; i < listed; ++i) {
      if (confirmers[static_cast<std::size_t>(i)] == k) return confirmed - 1;
    }
    return confirmed;
  }
};

/// The votes by voxel key (a flat index into one array: the look-ups below, 27 per distinct
/// voxel of a held region, cost a third of what std::unordered_map's do).
class Votes {
 public:
  VoxelVotes& at(std::uint64_t key) {
    const auto [i, inserted] = index_.tryEmplace(key, static_cast<std::uint32_t>(votes_.size()));
    if (inserted) votes_.emplace_back();
    return votes_[i];
  }
  const VoxelVotes* find(std::uint64_t key) const {
    const std::uint32_t i = index_.find(key);
    return i == FlatIndex::kMissing ? nullptr : &votes_[i];
  }

 private:
  FlatIndex index_;
  std::vector<VoxelVotes> votes_;
};

/// Keyframe k's held pixels whose voxel (26 neighbours included) at least `min_keyframes` other
/// keyframes confirmed static, and more than saw motion there; empty if none.
cv::Mat confirmedHeldPixels(const PinholeCamera& camera, const HeldKeyframe& kf, int k,
                            const Votes& votes, float inv, int min_keyframes) {
  if (kf.held.empty() || kf.depth_m.size() != kf.held.size()) return {};
  cv::Mat hit = cv::Mat::zeros(kf.held.size(), CV_8UC1);
  bool any = false;
  // Neighbouring pixels mostly fall into one voxel (3 cm at 2 m: ~8 pixels): the verdict of the
  // last voxel looked up is kept.
  std::uint64_t last_key = 0;
  bool last_found = false, have_last = false;
  for (int v = 0; v < kf.held.rows; ++v) {
    const std::uint8_t* h = kf.held.ptr<std::uint8_t>(v);
    const float* z = kf.depth_m.ptr<float>(v);
    for (int u = 0; u < kf.held.cols; ++u) {
      if (h[u] == 0 || !(z[u] > 0.0f)) continue;
      const std::uint64_t at =
          vis::voxelKey((kf.T_W_C * camera.backProject(u, v, z[u])).cast<float>(), inv);
      if (!have_last || at != last_key) {
        int confirmed = 0, moved = 0;  // the most of each around it
        for (int dz = -1; dz <= 1; ++dz) {
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
              const VoxelVotes* near = votes.find(vis::offsetKey(at, dx, dy, dz));
              if (near == nullptr) continue;
              confirmed = std::max(confirmed, near->confirmedByOthers(k));
              moved = std::max(moved, near->moved);
            }
          }
        }
        last_key = at, have_last = true;
        last_found = confirmed >= min_keyframes && confirmed > moved;
      }
      if (last_found) hit.at<std::uint8_t>(v, u) = 255, any = true;
    }
  }
  return any ? hit : cv::Mat();
}

}  // namespace

std::vector<Eigen::Vector3f> maskPoints(const PinholeCamera& camera, const cv::Mat& depth_m,
                                        const cv::Mat& mask, int stride_px) {
  std::vector<Eigen::Vector3f> out;
  if (mask.empty() || depth_m.empty() || mask.size() != depth_m.size()) return out;
  const int step = std::max(1, stride_px);
  for (int v = step / 2; v < depth_m.rows; v += step) {
    for (int u = step / 2; u < depth_m.cols; u += step) {
      const float z = depth_m.at<float>(v, u);
      if (mask.at<std::uint8_t>(v, u) == 0 || !(z > 0.0f)) continue;
      out.push_back(camera.backProject(u, v, z).cast<float>());
    }
  }
  return out;
}

std::vector<cv::Mat> heldConfirmedElsewhere(const PinholeCamera& camera,
                                            const std::vector<HeldKeyframe>& keyframes,
                                            double voxel_m, int min_keyframes) {
  std::vector<cv::Mat> out(keyframes.size());
  if (voxel_m <= 0.0) return out;
  const auto inv = static_cast<float>(1.0 / voxel_m);
  const auto key = [inv](const Eigen::Vector3d& p_W) {
    return vis::voxelKey(p_W.cast<float>(), inv);
  };
  Votes votes;
  bool any_confirmed = false;
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    // A keyframe counts once per voxel: a point in the voxel of the point before it adds nothing.
    std::uint64_t last = 0;
    bool have_last = false;
    for (const Eigen::Vector3f& p_C : keyframes[k].confirmed_C) {
      const std::uint64_t at = key(keyframes[k].T_W_C * p_C.cast<double>());
      if (!have_last || at != last) votes.at(at).confirm(static_cast<int>(k));
      last = at, have_last = true, any_confirmed = true;
    }
    have_last = false;
    for (const Eigen::Vector3f& p_C : keyframes[k].moved_C) {
      const std::uint64_t at = key(keyframes[k].T_W_C * p_C.cast<double>());
      if (!have_last || at != last) votes.at(at).move(static_cast<int>(k));
      last = at, have_last = true;
    }
  }
  if (!any_confirmed) return out;
  // The votes are read only from here on: every other keyframe on the other thread.
  inTwo([&](int half) {
    for (std::size_t k = static_cast<std::size_t>(half); k < keyframes.size(); k += 2)
      out[k] =
          confirmedHeldPixels(camera, keyframes[k], static_cast<int>(k), votes, inv, min_keyframes);
  });
  return out;
}

}  // namespace dynamap
