#include "io/obj_triangles.hpp"

#include <charconv>
#include <cmath>

#include "core/input_error.hpp"
#include "io/height_image.hpp"

namespace ps::io {

namespace {

[[noreturn]] void fail(const std::string& name, std::size_t line, const std::string& what) {
  throw core::InputError(name + ":" + std::to_string(line) + ": " + what);
}

// The whitespace-separated words of one line.
std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

}  // namespace

ObjTriangles parseObjTriangles(std::string_view text, const std::string& name) {
  ObjTriangles out;
  std::size_t lineNo = 0, pos = 0;
  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++lineNo;
    const auto w = words(line);
    if (w.empty() || w[0][0] == '#') continue;
    if (w[0] == "v") {
      if (w.size() < 4) fail(name, lineNo, "a vertex needs x y z");
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) {
        const std::string_view s = w[std::size_t(k + 1)];
        double x = 0;
        const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
        if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(x))
          fail(name, lineNo, "'" + std::string(s) + "' is not a finite number");
        p[k] = x;
      }
      out.vertices.push_back(p);
    } else if (w[0] == "f") {
      if (w.size() != 4)
        fail(name, lineNo,
             "a face with " + std::to_string(w.size() - 1) +
                 " corners: a road must be a triangle mesh (triangulate it before export)");
      std::array<std::uint32_t, 3> t{};
      for (int k = 0; k < 3; ++k) {
        std::string_view s = w[std::size_t(k + 1)];
        s = s.substr(0, s.find('/'));  // "v/vt/vn": the vertex
        long long index = 0;
        const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), index);
        if (ec != std::errc() || ptr != s.data() + s.size() || index == 0)
          fail(name, lineNo, "'" + std::string(w[std::size_t(k + 1)]) + "' is not a vertex index");
        const long long n = (long long)out.vertices.size();
        const long long zeroBased = index > 0 ? index - 1 : n + index;  // negative: relative
        if (zeroBased < 0 || zeroBased >= n)
          fail(name, lineNo,
               "vertex index " + std::to_string(index) + " is out of range (" + std::to_string(n) +
                   " vertices so far)");
        t[std::size_t(k)] = std::uint32_t(zeroBased);
      }
      if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
        fail(name, lineNo, "a triangle repeats a vertex");
      out.triangles.push_back(t);
    } else if (w[0] == "l" || w[0] == "p") {
      fail(name, lineNo, "lines and points are not a triangle mesh");
    }
  }
  if (out.triangles.empty())
    throw core::InputError(name + ": no triangles (a road is a mesh of triangles)");
  return out;
}

ObjTriangles readObjTriangles(const std::filesystem::path& path) {
  const std::vector<unsigned char> bytes = readFileBytes(path, std::uint64_t(1) << 30);
  return parseObjTriangles(
      std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path.string());
}

}  // namespace ps::io
