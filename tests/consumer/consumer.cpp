// Tracks the first N frames of a TUM folder with an installed dynamap::System and checks the
// poses: finite, the first one the identity, and equal (1e-6) to `dynamap run`'s trajectory.
//   consumer SEQUENCE_DIR CONFIG_YAML N CLI_TRAJECTORY_TXT
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <dynamap/system.hpp>
#include <opencv2/imgcodecs.hpp>

namespace {

std::map<double, std::string> readList(const std::string& dir, const std::string& name) {
  std::map<double, std::string> out;
  std::ifstream in(dir + "/" + name);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    double t = 0.0;
    std::string path;
    if (line.empty() || line[0] == '#' || !(fields >> t >> path)) continue;
    out[t] = dir + "/" + path;
  }
  return out;
}

/// TUM associate.py: closest colour/depth pairs first (< 0.02 s), each stamp used once.
std::map<double, double> associate(const std::map<double, std::string>& rgb,
                                   const std::map<double, std::string>& depth) {
  std::vector<std::tuple<double, double, double>> candidates;
  for (const auto& [a, unused_a] : rgb) {
    for (auto it = depth.lower_bound(a - 0.02); it != depth.end() && it->first < a + 0.02; ++it) {
      if (std::abs(a - it->first) < 0.02)
        candidates.emplace_back(std::abs(a - it->first), a, it->first);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::map<double, double> pairs;
  std::set<double> used;
  for (const auto& [d, a, b] : candidates) {
    if (pairs.count(a) == 0 && used.insert(b).second) pairs[a] = b;
  }
  return pairs;
}

int fail(const std::string& what) {
  std::fprintf(stderr, "consumer: FAILED: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) return fail("usage: consumer SEQUENCE_DIR CONFIG_YAML N CLI_TRAJECTORY_TXT");
  const std::string dir = argv[1];
  const std::size_t n = std::stoul(argv[3]);
  const auto rgb = readList(dir, "rgb.txt");
  const auto depth = readList(dir, "depth.txt");
  const auto pairs = associate(rgb, depth);

  auto system = dynamap::System::fromConfig(argv[2], {});
  for (const auto& [t, rgb_path] : rgb) {
    if (system->counts().frames == n) break;
    const cv::Mat bgr = cv::imread(rgb_path, cv::IMREAD_COLOR);
    const auto d = pairs.find(t);
    const cv::Mat depth_raw = d == pairs.end()
                                  ? cv::Mat(cv::Mat::zeros(bgr.size(), CV_16UC1))
                                  : cv::imread(depth.at(d->second), cv::IMREAD_UNCHANGED);
    const dynamap::TrackOutput out = system->track(bgr, depth_raw, t);
    std::printf("%.6f %s keyframe=%d\n", t, dynamap::toString(out.status), out.is_keyframe ? 1 : 0);
  }
  system->finish();
  const auto trajectory = system->trajectory();

  std::ifstream cli(argv[4]);
  std::vector<std::vector<double>> cli_rows;
  for (std::string line; std::getline(cli, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::vector<double> row(8);
    for (double& v : row) fields >> v;
    cli_rows.push_back(row);
  }
  if (trajectory.size() != n) return fail("expected " + std::to_string(n) + " poses");
  if (cli_rows.size() != n) return fail("CLI trajectory has " + std::to_string(cli_rows.size()));
  if (!trajectory[0].T_W_C.matrix().isIdentity(1e-12)) return fail("first pose not identity");
  double max_diff_m = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& T = trajectory[i].T_W_C;
    if (!T.matrix().allFinite()) return fail("pose " + std::to_string(i) + " not finite");
    if (std::abs(trajectory[i].timestamp_s - cli_rows[i][0]) > 1e-6) return fail("timestamps");
    for (int k = 0; k < 3; ++k) {
      max_diff_m = std::max(max_diff_m, std::abs(T.translation()[k] - cli_rows[i][1 + k]));
    }
  }
  std::printf("consumer: %zu poses, max position difference to the CLI %.3g m\n", n, max_diff_m);
  return max_diff_m <= 1e-6 ? 0 : fail("positions differ from the CLI's by more than 1e-6 m");
}
