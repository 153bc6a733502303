// MappingWorker::importMap(): a saved map as the backend's first content.
#include "dynamap/mapping/mapping_worker.hpp"

namespace dynamap {

bool MappingWorker::importMap(const std::string& dir) {
  std::lock_guard<std::mutex> lock(backend_mutex_);
  return backend_->importMap(dir);
}

}  // namespace dynamap
