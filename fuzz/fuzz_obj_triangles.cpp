// libFuzzer: road meshes for `overlay` (io::parseObjTriangles). Any input must parse or be
// refused with core::InputError; what parses has finite vertices, indices in range and no
// repeated corner, and written back as plain OBJ it parses to the same mesh.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/input_error.hpp"
#include "io/obj_triangles.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ps::io::ObjTriangles mesh;
  try {
    mesh = ps::io::parseObjTriangles(text, "fuzz.obj");
  } catch (const ps::core::InputError&) {
    return 0;
  }
  std::string again;
  char line[160];
  for (const auto& v : mesh.vertices) {
    if (!v.allFinite()) std::abort();
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", v.x(), v.y(), v.z());
    again += line;
  }
  for (const auto& t : mesh.triangles) {
    for (const auto i : t)
      if (i >= mesh.vertices.size()) std::abort();
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) std::abort();
    again += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
             std::to_string(t[2] + 1) + "\n";
  }
  try {
    const ps::io::ObjTriangles back = ps::io::parseObjTriangles(again, "again.obj");
    if (back.vertices != mesh.vertices || back.triangles != mesh.triangles) std::abort();
  } catch (const ps::core::InputError&) {
    std::abort();  // what we wrote must read back
  }
  return 0;
}
