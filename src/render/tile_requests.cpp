#include "render/tile_requests.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>

namespace ps::render {

TilePyramid TilePyramid::forGrid(const core::GridSize& grid, int maxTileCells) {
  TilePyramid p;
  p.m = grid.m();
  p.tileCells = std::min(maxTileCells, p.m);
  p.coarsest = 0;
  while ((p.m >> p.coarsest) > p.tileCells) ++p.coarsest;
  return p;
}

std::size_t TilePyramid::tileCount() const {
  std::size_t n = 0;
  for (int l = 0; l <= coarsest; ++l)
    n += std::size_t(tilesPerSide(l)) * std::size_t(tilesPerSide(l));
  return n;
}

std::size_t TilePyramid::index(const TileKey& k) const {
  // Coarsest level first: its tiles are the always-resident ones, and the offsets stay small.
  std::size_t offset = 0;
  for (int l = coarsest; l > k.level; --l)
    offset += std::size_t(tilesPerSide(l)) * std::size_t(tilesPerSide(l));
  return offset + std::size_t(k.ty) * std::size_t(tilesPerSide(k.level)) + std::size_t(k.tx);
}

TileKey TilePyramid::key(std::size_t i) const {
  for (int l = coarsest; l >= 0; --l) {
    const std::size_t n = std::size_t(tilesPerSide(l));
    if (i < n * n) return {l, int(i % n), int(i / n)};
    i -= n * n;
  }
  return {-1, 0, 0};
}

std::vector<TileWish> tileWishes(const TilePyramid& pyramid, const terrain::Mesh& mesh,
                                 const terrain::Camera& camera, int gridSide) {
  const Eigen::Matrix3f rotation = camera.rotation.cast<float>();
  const Eigen::Vector3f offset = (mesh.eye - camera.eye).cast<float>();
  const std::size_t n = mesh.positions.size();
  std::vector<Eigen::Vector3f> cam(n);
  for (std::size_t i = 0; i < n; ++i) cam[i] = rotation * (mesh.positions[i] + offset);
  const float fx = float(camera.fx), fy = float(camera.fy), cx = float(camera.cx),
              cy = float(camera.cy), w = float(camera.width), h = float(camera.height);
  std::vector<TileWish> wishes;
  wishes.reserve(mesh.triangleCount());
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    std::array<Eigen::Vector2f, 3> s, g;
    s.fill(Eigen::Vector2f::Zero());
    g.fill(Eigen::Vector2f::Zero());
    TileWish wish;
    wish.u0 = wish.v0 = gridSide;
    wish.u1 = wish.v1 = -1;
    bool behind = false;
    float zMin = INFINITY, zSum = 0;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t vi = mesh.indices[t + std::size_t(k)];
      const Eigen::Vector3f& p = cam[vi];
      const int u = int(mesh.gridIndex[vi] % std::uint64_t(gridSide)),
                v = int(mesh.gridIndex[vi] / std::uint64_t(gridSide));
      g[std::size_t(k)] = {float(u), float(v)};
      wish.u0 = std::min(wish.u0, u);
      wish.u1 = std::max(wish.u1, u);
      wish.v0 = std::min(wish.v0, v);
      wish.v1 = std::max(wish.v1, v);
      if (!(p.z() > 0)) {
        behind = true;
        continue;
      }
      s[std::size_t(k)] = {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
      zMin = std::min(zMin, p.z());
      zSum += p.z();
    }
    if (behind) {
      wish.level = 0;
      wishes.push_back(wish);
      continue;
    }
    // Wholly off one side of the image: not seen.
    auto allOff = [&](auto&& off) { return off(s[0]) && off(s[1]) && off(s[2]); };
    if (allOff([](const Eigen::Vector2f& q) { return q.x() < -1; }) ||
        allOff([&](const Eigen::Vector2f& q) { return q.x() > w; }) ||
        allOff([](const Eigen::Vector2f& q) { return q.y() < -1; }) ||
        allOff([&](const Eigen::Vector2f& q) { return q.y() > h; }))
      continue;
    Eigen::Matrix2f screen, grid;
    screen << s[1] - s[0], s[2] - s[0];
    grid << g[1] - g[0], g[2] - g[0];
    const float det = screen.determinant();
    if (!(std::abs(det) > 1e-6f)) continue;  // edge-on: no pixels of its own
    // Grid per pixel, as fwidth sees it: |d/dx| + |d/dy| for each grid axis.
    const Eigen::Matrix2f jacobian = grid * screen.inverse();
    const float footprint = std::max(std::abs(jacobian(0, 0)) + std::abs(jacobian(0, 1)),
                                     std::abs(jacobian(1, 0)) + std::abs(jacobian(1, 1))) *
                            zMin / (zSum / 3);
    wish.level =
        footprint > 1 ? std::min(pyramid.coarsest, int(std::floor(std::log2(footprint)))) : 0;
    wishes.push_back(wish);
  }
  return wishes;
}

void tilesFor(const TilePyramid& pyramid, const std::vector<TileWish>& wishes, int bias,
              std::vector<std::uint32_t>& stamp, std::uint32_t stampValue,
              std::vector<std::uint32_t>& out) {
  out.clear();
  stamp.resize(pyramid.tileCount(), 0);
  for (const TileWish& w : wishes) {
    const int level = std::min(pyramid.coarsest, w.level + bias);
    const int span = pyramid.tileCells << level;  // level-0 cells per tile
    const int last = pyramid.tilesPerSide(level) - 1;
    const int tx0 = std::min(w.u0 / span, last), tx1 = std::min(w.u1 / span, last);
    const int ty0 = std::min(w.v0 / span, last), ty1 = std::min(w.v1 / span, last);
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) {
        const std::size_t i = pyramid.index({level, tx, ty});
        if (stamp[i] == stampValue) continue;
        stamp[i] = stampValue;
        out.push_back(std::uint32_t(i));
      }
  }
}

}  // namespace ps::render
