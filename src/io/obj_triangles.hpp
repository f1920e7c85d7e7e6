#pragma once
// Reading a triangle mesh from a Wavefront OBJ (a road for `overlay`): `v x y z` and
// `f a b c` lines (a/b/c forms and negative, relative indices as OBJ allows); everything else
// OBJ may hold (normals, texture coordinates, groups, materials, comments) is skipped.
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace ps::io {

struct ObjTriangles {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// Throws core::InputError "<name>:<line>: <what is wrong>" for a malformed number, a face that
// is not a triangle, an index out of range, a non-finite coordinate, or no triangle at all.
ObjTriangles parseObjTriangles(std::string_view text, const std::string& name);
ObjTriangles readObjTriangles(const std::filesystem::path& path);

}  // namespace ps::io
