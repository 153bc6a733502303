#include "dynamap/core/tracking/place_recognition.hpp"

#include <algorithm>
#include <unordered_map>

#include <opencv2/flann.hpp>

namespace dynamap {

PlaceRecognizer::PlaceRecognizer(const PlaceRecognitionParams& params) : params_(params) {}
PlaceRecognizer::~PlaceRecognizer() = default;

void PlaceRecognizer::add(int keyframe, const cv::Mat& descriptors) {
  CV_Assert(descriptors.empty() || descriptors.type() == CV_8UC1);
  if (!descriptors.empty()) {
    recent_.descriptors.push_back(descriptors);
    recent_.owner.insert(recent_.owner.end(), static_cast<std::size_t>(descriptors.rows), keyframe);
  }
  ++recent_.keyframes;
  ++keyframes_;
  if (recent_.keyframes >= params_.chunk_keyframes) seal();
}

void PlaceRecognizer::seal() {
  chunks_.push_back(std::move(recent_));
  recent_ = Chunk{};
  // Binary-counter merging: two neighbours of the same size become one of twice the size.
  while (chunks_.size() >= 2 &&
         chunks_[chunks_.size() - 2].keyframes == chunks_.back().keyframes) {
    Chunk last = std::move(chunks_.back());
    chunks_.pop_back();
    Chunk& into = chunks_.back();
    into.index.reset();
    into.descriptors.push_back(last.descriptors);
    into.owner.insert(into.owner.end(), last.owner.begin(), last.owner.end());
    into.keyframes += last.keyframes;
  }
  if (!chunks_.back().index) buildIndex(chunks_.back());
}

void PlaceRecognizer::buildIndex(Chunk& chunk) const {
  if (chunk.descriptors.rows == 0) return;
  chunk.index = std::make_unique<cv::flann::Index>(
      chunk.descriptors,
      cv::flann::LshIndexParams(params_.lsh_tables, params_.lsh_key_bits, params_.lsh_multi_probe),
      cvflann::FLANN_DIST_HAMMING);
}

void PlaceRecognizer::vote(const Chunk& chunk, const cv::Mat& query,
                           std::vector<std::vector<int>>& hits) const {
  if (chunk.descriptors.rows == 0) return;
  const int k = std::min(params_.neighbours, chunk.descriptors.rows);
  cv::Mat indices, dists;
  if (chunk.index) {
    chunk.index->knnSearch(query, indices, dists, k, cv::flann::SearchParams());
  } else {
    cv::batchDistance(query, chunk.descriptors, dists, CV_32S, indices, cv::NORM_HAMMING, k);
  }
  if (dists.type() != CV_32S) dists.convertTo(dists, CV_32S);
  for (int q = 0; q < query.rows; ++q) {
    for (int j = 0; j < k; ++j) {
      const int t = indices.at<int>(q, j);
      if (t < 0 || t >= chunk.descriptors.rows || dists.at<int>(q, j) > params_.max_hamming) {
        continue;
      }
      hits[static_cast<std::size_t>(q)].push_back(chunk.owner[static_cast<std::size_t>(t)]);
    }
  }
}

std::vector<PlaceCandidate> PlaceRecognizer::query(const cv::Mat& descriptors,
                                                   const std::function<bool(int)>& allowed,
                                                   int max_results) const {
  if (descriptors.empty() || keyframes_ == 0) return {};
  std::vector<std::vector<int>> hits(static_cast<std::size_t>(descriptors.rows));
  for (const Chunk& chunk : chunks_) vote(chunk, descriptors, hits);
  vote(recent_, descriptors, hits);
  std::unordered_map<int, int> votes;
  for (auto& h : hits) {
    std::sort(h.begin(), h.end());
    h.erase(std::unique(h.begin(), h.end()), h.end());
    for (const int keyframe : h) ++votes[keyframe];
  }
  std::vector<PlaceCandidate> out;
  for (const auto& [keyframe, count] : votes) {
    if (allowed(keyframe)) out.push_back({keyframe, count});
  }
  std::sort(out.begin(), out.end(), [](const PlaceCandidate& a, const PlaceCandidate& b) {
    return a.votes != b.votes ? a.votes > b.votes : a.keyframe < b.keyframe;
  });
  if (static_cast<int>(out.size()) > max_results) out.resize(static_cast<std::size_t>(max_results));
  return out;
}

}  // namespace dynamap
