#pragma once
// Marker families as the two detector libraries name them, and the canonical marker images.
//
// A family is named exactly as its library names it: AprilTag's `tag36h11`, `tag25h9`,
// `tag16h5`, `tag36h10`, `tagStandard41h12`, `tagStandard52h13`, `tagCircle21h7`,
// `tagCircle49h12`, `tagCustom48h12`, and OpenCV's `DICT_4X4_50` ... `DICT_ARUCO_ORIGINAL`,
// `DICT_APRILTAG_36h11` ...
//
// The canonical image of a marker (what `planetsculpt markers` prints and `planetsculpt synth`
// renders) fixes which corner is its top-left: for AprilTag families the official tag image
// (apriltag_to_image), for OpenCV dictionaries cv::aruco::drawMarker. Both detector back ends
// report corners TL, TR, BR, BL of that image.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ps::tracking {

enum class Backend { kAuto, kAruco, kAprilTag };
std::string toString(Backend b);
Backend backendFromString(const std::string& s);  // "auto" | "aruco" | "apriltag"; InputError

struct FamilyInfo {
  std::string name;          // as given (canonical spelling)
  bool apriltag = false;     // an AprilTag family (both back ends for the four classic ones)
  int arucoDictionary = -1;  // cv::aruco predefined dictionary, or -1 if aruco cannot read it
  // The OpenCV dictionary's marker is the official tag rotated by this many quarter turns
  // (clockwise); the aruco back end rotates its corners back.
  int arucoQuarterTurns = 0;
  int markerCount = 0;
  // Canonical image: totalCells x totalCells cells, the marker's edge (the black border's outer
  // edge, what "marker size" measures) spans edgeCells cells starting at cell edgeOffset.
  int totalCells = 0, edgeCells = 0, edgeOffset = 0;
};

// Throws core::InputError listing the known names for an unknown family.
FamilyInfo familyInfo(const std::string& name);
std::vector<std::string> knownFamilies();

// The canonical image of marker `id`, one byte per cell (0 black, 255 white), totalCells
// square, including a white quiet zone of at least one cell. InputError for a bad id.
cv::Mat markerCells(const std::string& family, int id);

// The same scaled to `cellPixels` pixels per cell (nearest neighbour: sharp edges).
cv::Mat markerImage(const std::string& family, int id, int cellPixels);

}  // namespace ps::tracking
