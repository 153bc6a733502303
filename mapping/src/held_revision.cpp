#include "dynamap/mapping/held_revision.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace dynamap {
namespace {

constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisOffset = std::int64_t{1} << (kAxisBits - 1);
constexpr std::uint64_t kAxisMask = (std::uint64_t{1} << kAxisBits) - 1;

std::uint64_t cellKey(std::int64_t x, std::int64_t y, std::int64_t z) {
  const auto c = [](std::int64_t v) {
    return static_cast<std::uint64_t>(v + kAxisOffset) & kAxisMask;
  };
  return c(x) | (c(y) << kAxisBits) | (c(z) << (2 * kAxisBits));
}

/// The keyframes that confirmed a voxel (the first kMaxConfirmers of them).
constexpr int kMaxConfirmers = 4;
struct Confirmers {
  std::array<int, kMaxConfirmers> by{};
  int n = 0;
  void add(int k) {
    for (int i = 0; i < n; ++i) {
      if (by[static_cast<std::size_t>(i)] == k) return;
    }
    if (n < kMaxConfirmers) by[static_cast<std::size_t>(n++)] = k;
  }
  int others(int k) const {
    int count = 0;
    for (int i = 0; i < n; ++i) count += by[static_cast<std::size_t>(i)] != k ? 1 : 0;
    return count;
  }
};

}  // namespace

std::vector<Eigen::Vector3f> confirmedPoints(const PinholeCamera& camera, const cv::Mat& depth_m,
                                             const cv::Mat& confirmed, int stride_px) {
  std::vector<Eigen::Vector3f> out;
  if (confirmed.empty() || depth_m.empty() || confirmed.size() != depth_m.size()) return out;
  const int step = std::max(1, stride_px);
  for (int v = step / 2; v < depth_m.rows; v += step) {
    for (int u = step / 2; u < depth_m.cols; u += step) {
      const float z = depth_m.at<float>(v, u);
      if (confirmed.at<std::uint8_t>(v, u) == 0 || !(z > 0.0f)) continue;
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
  const double inv = 1.0 / voxel_m;
  const auto cell = [inv](const Eigen::Vector3d& p, std::int64_t c[3]) {
    for (int a = 0; a < 3; ++a) c[a] = static_cast<std::int64_t>(std::floor(p[a] * inv));
  };
  std::unordered_map<std::uint64_t, Confirmers> confirmed;
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    for (const Eigen::Vector3f& p_C : keyframes[k].confirmed_C) {
      std::int64_t c[3];
      cell(keyframes[k].T_W_C * p_C.cast<double>(), c);
      confirmed[cellKey(c[0], c[1], c[2])].add(static_cast<int>(k));
    }
  }
  if (confirmed.empty()) return out;
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    const HeldKeyframe& kf = keyframes[k];
    if (kf.held.empty() || kf.depth_m.size() != kf.held.size()) continue;
    cv::Mat hit = cv::Mat::zeros(kf.held.size(), CV_8UC1);
    bool any = false;
    for (int v = 0; v < kf.held.rows; ++v) {
      const std::uint8_t* h = kf.held.ptr<std::uint8_t>(v);
      const float* z = kf.depth_m.ptr<float>(v);
      for (int u = 0; u < kf.held.cols; ++u) {
        if (h[u] == 0 || !(z[u] > 0.0f)) continue;
        std::int64_t c[3];
        cell(kf.T_W_C * camera.backProject(u, v, z[u]), c);
        bool found = false;
        for (int dz = -1; dz <= 1 && !found; ++dz) {
          for (int dy = -1; dy <= 1 && !found; ++dy) {
            for (int dx = -1; dx <= 1 && !found; ++dx) {
              const auto it = confirmed.find(cellKey(c[0] + dx, c[1] + dy, c[2] + dz));
              found =
                  it != confirmed.end() && it->second.others(static_cast<int>(k)) >= min_keyframes;
            }
          }
        }
        if (found) hit.at<std::uint8_t>(v, u) = 255, any = true;
      }
    }
    if (any) out[k] = hit;
  }
  return out;
}

}  // namespace dynamap
