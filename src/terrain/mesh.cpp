#include "terrain/mesh.hpp"

#include <atomic>

namespace ps::terrain {

std::uint64_t nextMeshGeneration() {
  static std::atomic<std::uint64_t> counter{1};
  return counter.fetch_add(1);
}

}  // namespace ps::terrain
