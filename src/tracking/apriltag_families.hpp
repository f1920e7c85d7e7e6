#pragma once
// The AprilTag C library's families by name (internal to ps_tracking).
#include <memory>
#include <string>

extern "C" {
#include <apriltag/apriltag.h>
}

namespace ps::tracking::detail {

struct FamilyDeleter {
  void (*destroy)(apriltag_family_t*) = nullptr;
  void operator()(apriltag_family_t* f) const {
    if (f && destroy) destroy(f);
  }
};
using FamilyPtr = std::unique_ptr<apriltag_family_t, FamilyDeleter>;

// nullptr when the name is not an AprilTag family.
FamilyPtr createAprilTagFamily(const std::string& name);
bool isAprilTagFamily(const std::string& name);
// The four families OpenCV also has as DICT_APRILTAG_*; -1 otherwise.
int arucoDictionaryForAprilTag(const std::string& name);

}  // namespace ps::tracking::detail
