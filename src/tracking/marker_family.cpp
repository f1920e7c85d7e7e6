#include "tracking/marker_family.hpp"

#include <algorithm>
#include <array>
#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include "core/input_error.hpp"
#include "core/named_values.hpp"
#include "tracking/apriltag_families.hpp"

extern "C" {
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h10.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagCircle49h12.h>
#include <apriltag/tagCustom48h12.h>
#include <apriltag/tagStandard41h12.h>
#include <apriltag/tagStandard52h13.h>
}

namespace ps::tracking {

namespace detail {
namespace {
struct AprilTagEntry {
  const char* name;
  apriltag_family_t* (*create)();
  void (*destroy)(apriltag_family_t*);
  int aruco;
};
const std::array<AprilTagEntry, 9> kAprilTag = {{
    {"tag16h5", tag16h5_create, tag16h5_destroy, cv::aruco::DICT_APRILTAG_16h5},
    {"tag25h9", tag25h9_create, tag25h9_destroy, cv::aruco::DICT_APRILTAG_25h9},
    {"tag36h10", tag36h10_create, tag36h10_destroy, cv::aruco::DICT_APRILTAG_36h10},
    {"tag36h11", tag36h11_create, tag36h11_destroy, cv::aruco::DICT_APRILTAG_36h11},
    {"tagCircle21h7", tagCircle21h7_create, tagCircle21h7_destroy, -1},
    {"tagCircle49h12", tagCircle49h12_create, tagCircle49h12_destroy, -1},
    {"tagCustom48h12", tagCustom48h12_create, tagCustom48h12_destroy, -1},
    {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy, -1},
    {"tagStandard52h13", tagStandard52h13_create, tagStandard52h13_destroy, -1},
}};

const AprilTagEntry* findAprilTag(const std::string& name) {
  for (const auto& e : kAprilTag)
    if (name == e.name) return &e;
  return nullptr;
}
}  // namespace

FamilyPtr createAprilTagFamily(const std::string& name) {
  const auto* e = findAprilTag(name);
  if (!e) return FamilyPtr(nullptr, FamilyDeleter{});
  return FamilyPtr(e->create(), FamilyDeleter{e->destroy});
}
bool isAprilTagFamily(const std::string& name) {
  return findAprilTag(name) != nullptr;
}
int arucoDictionaryForAprilTag(const std::string& name) {
  const auto* e = findAprilTag(name);
  return e ? e->aruco : -1;
}
}  // namespace detail

namespace {
const std::array<const char*, 21> kArucoNames = {
    "DICT_4X4_50",         "DICT_4X4_100",       "DICT_4X4_250",       "DICT_4X4_1000",
    "DICT_5X5_50",         "DICT_5X5_100",       "DICT_5X5_250",       "DICT_5X5_1000",
    "DICT_6X6_50",         "DICT_6X6_100",       "DICT_6X6_250",       "DICT_6X6_1000",
    "DICT_7X7_50",         "DICT_7X7_100",       "DICT_7X7_250",       "DICT_7X7_1000",
    "DICT_ARUCO_ORIGINAL", "DICT_APRILTAG_16h5", "DICT_APRILTAG_25h9", "DICT_APRILTAG_36h10",
    "DICT_APRILTAG_36h11"};

bool classicAprilTag(const std::string& name) {
  return name == "tag16h5" || name == "tag25h9" || name == "tag36h10" || name == "tag36h11";
}
}  // namespace

constexpr core::NameTable<Backend, 3> kBackends{
    "detector back end",
    {{{Backend::kAuto, "auto"}, {Backend::kAruco, "aruco"}, {Backend::kAprilTag, "apriltag"}}}};

std::string toString(Backend b) {
  return kBackends.nameOf(b);
}

Backend backendFromString(const std::string& s) {
  return kBackends.parse(s);
}

std::vector<std::string> knownFamilies() {
  std::vector<std::string> all;
  for (const auto& e : detail::kAprilTag) all.emplace_back(e.name);
  for (const char* n : kArucoNames) all.emplace_back(n);
  return all;
}

FamilyInfo familyInfo(const std::string& name) {
  FamilyInfo info;
  info.name = name;
  if (auto fam = detail::createAprilTagFamily(name)) {
    info.apriltag = true;
    info.arucoDictionary = detail::arucoDictionaryForAprilTag(name);
    // OpenCV's DICT_APRILTAG_* markers are the official tags turned by 180 degrees (checked
    // against apriltag_to_image in tests/test_tracking_detect.cpp).
    info.arucoQuarterTurns = info.arucoDictionary >= 0 ? 2 : 0;
    info.markerCount = int(fam->ncodes);
    const int extra = classicAprilTag(name) ? 0 : 1;  // a white ring around the data bits
    info.totalCells = int(fam->total_width) + 2 * extra;
    info.edgeCells = int(fam->width_at_border);
    info.edgeOffset = (int(fam->total_width) - int(fam->width_at_border)) / 2 + extra;
    return info;
  }
  for (int i = 0; i < int(kArucoNames.size()); ++i) {
    if (name != kArucoNames[std::size_t(i)]) continue;
    const auto dict = cv::aruco::getPredefinedDictionary(i);
    info.arucoDictionary = i;
    info.markerCount = dict->bytesList.rows;
    info.edgeCells = dict->markerSize + 2;
    info.totalCells = info.edgeCells + 2;
    info.edgeOffset = 1;
    return info;
  }
  std::string known;
  for (const auto& n : knownFamilies()) known += (known.empty() ? "" : ", ") + n;
  throw core::InputError("unknown marker family '" + name + "' (known: " + known + ")");
}

cv::Mat markerCells(const std::string& family, int id) {
  const FamilyInfo info = familyInfo(family);
  if (id < 0 || id >= info.markerCount)
    throw core::InputError("marker id " + std::to_string(id) + " is not in " + family + " (0.." +
                           std::to_string(info.markerCount - 1) + ")");
  cv::Mat cells(info.totalCells, info.totalCells, CV_8U, cv::Scalar(255));
  if (info.apriltag) {
    auto fam = detail::createAprilTagFamily(family);
    image_u8_t* im = apriltag_to_image(fam.get(), id);
    const int off = (info.totalCells - im->width) / 2;
    for (int y = 0; y < im->height; ++y)
      for (int x = 0; x < im->width; ++x)
        cells.at<uchar>(off + y, off + x) = im->buf[y * im->stride + x] ? 255 : 0;
    image_u8_destroy(im);
  } else {
    const auto dict = cv::aruco::getPredefinedDictionary(info.arucoDictionary);
    cv::Mat inner;
    cv::aruco::drawMarker(dict, id, info.edgeCells, inner, 1);
    inner.copyTo(cells(cv::Rect(1, 1, info.edgeCells, info.edgeCells)));
  }
  return cells;
}

cv::Mat markerImage(const std::string& family, int id, int cellPixels) {
  if (cellPixels < 1)
    throw core::InputError("marker cell size " + std::to_string(cellPixels) + " px is not >= 1");
  cv::Mat out;
  cv::resize(markerCells(family, id), out, {}, cellPixels, cellPixels, cv::INTER_NEAREST);
  return out;
}

}  // namespace ps::tracking
