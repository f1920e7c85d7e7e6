#include "tracking/body_pose.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>

#include "tracking/pose_refine.hpp"

namespace ps::tracking {

namespace {

// Seeds nearer than this in rotation (and 1 % of the distance in position) are one seed.
constexpr double kSameSeedAngle = 2.0 * M_PI / 180.0;
// An alternative must be turned at least this far from the best to count as its flip.
constexpr double kFlipAngle = 10.0 * M_PI / 180.0;
// Seeds come from this many of the largest markers in the image.
constexpr std::size_t kSeedMarkers = 3;

struct Correspondences {
  std::vector<cv::Point3d> object;  // body frame
  std::vector<cv::Point2d> image;
};

cv::Vec3d rvecOf(const Pose& p) {
  const Eigen::Vector3d r = p.rvec();
  return {r.x(), r.y(), r.z()};
}

// Polishes `seed` over every correspondence; returns the RMS (inf when the solver fails or the
// body ends up behind the camera).
double polish(const Correspondences& c, const CameraCalibration& calib, Pose& pose) {
  const double e = refinePose(c.object, c.image, calib, pose);
  return std::isfinite(e) && pose.t.z() > 0 ? e : std::numeric_limits<double>::infinity();
}

double imageArea(const Detection& d) {
  double a = 0;
  for (std::size_t k = 0; k < 4; ++k) a += d.corners[k].cross(d.corners[(k + 1) % 4]);
  return 0.5 * std::abs(a);
}

double reprojectionRms(const Correspondences& c, const CameraCalibration& calib, const Pose& p) {
  if (!p.finite() || p.t.z() <= 0) return std::numeric_limits<double>::infinity();
  std::vector<cv::Point2d> projected;
  cv::projectPoints(c.object, rvecOf(p), cv::Vec3d(p.t.x(), p.t.y(), p.t.z()), cv::Mat(calib.K),
                    calib.distortion, projected);
  double sum = 0;
  for (std::size_t k = 0; k < projected.size(); ++k) {
    const cv::Point2d d = projected[k] - c.image[k];
    sum += d.dot(d);
  }
  return std::sqrt(sum / double(projected.size()));
}

// How many of the layout's markers a body pose says the camera should have read (facing it
// within 60 degrees, every corner 4 px inside the image) that were not found. A planar flip
// turns the body's other faces toward or away from the camera, so this tells the two apart
// where their corners cannot; 0 without the image's size.
int unreadButVisible(const MarkerLayout& layout, const Pose& body,
                     const std::vector<const Detection*>& used, const CameraCalibration& calib) {
  if (calib.imageSize.width <= 0 || calib.imageSize.height <= 0) return 0;
  int missed = 0;
  const auto px = projectLayout(layout, body, calib);
  for (std::size_t i = 0; i < layout.markers.size(); ++i) {
    const LayoutMarker& m = layout.markers[i];
    if (std::any_of(used.begin(), used.end(), [&](const Detection* d) { return d->id == m.id; }))
      continue;
    const Pose inCamera = body * m.inBody();
    if (inCamera.R.col(2).dot(-inCamera.t.normalized()) < std::cos(60.0 * M_PI / 180.0)) continue;
    bool inside = true;
    for (const auto& p : px[i])
      inside &= p.x >= 4 && p.y >= 4 && p.x <= calib.imageSize.width - 5 &&
                p.y <= calib.imageSize.height - 5;
    missed += inside ? 1 : 0;
  }
  return missed;
}

}  // namespace

BodyPoseResult solveBodyPose(const MarkerLayout& layout, std::span<const Detection> detections,
                             const CameraCalibration& calibration, const Pose* previous,
                             double ambiguityRatio) {
  BodyPoseResult out;
  std::vector<const Detection*> used;
  std::vector<int> doubled;
  // A detection of another family is not the layout's marker, whatever its id.
  auto ofLayout = [&](const Detection& d) {
    return (d.family.empty() || d.family == layout.family) && layout.find(d.id);
  };
  for (const auto& d : detections) {
    if (!ofLayout(d)) continue;
    const auto same = std::count_if(detections.begin(), detections.end(), [&](const Detection& o) {
      return o.id == d.id && ofLayout(o);
    });
    if (same > 1) {
      if (std::find(doubled.begin(), doubled.end(), d.id) == doubled.end()) doubled.push_back(d.id);
      continue;
    }
    used.push_back(&d);
  }
  std::sort(used.begin(), used.end(),
            [](const Detection* a, const Detection* b) { return a->id < b->id; });
  for (int id : doubled)
    out.note += (out.note.empty() ? "" : "; ") + std::string("id ") + std::to_string(id) +
                " seen more than once; not used";
  if (used.empty()) return out;

  Correspondences all;
  for (const Detection* d : used) {
    const LayoutMarker& m = *layout.find(d->id);
    for (std::size_t k = 0; k < 4; ++k) {
      all.object.emplace_back(m.corners[k].x(), m.corners[k].y(), m.corners[k].z());
      all.image.push_back(d->corners[k]);
    }
  }

  // Seeds from the largest markers' own candidates (the best measured), carried to the body
  // frame, without repeats.
  std::vector<const Detection*> bySize = used;
  std::stable_sort(bySize.begin(), bySize.end(), [](const Detection* a, const Detection* b) {
    return imageArea(*a) > imageArea(*b);
  });
  bySize.resize(std::min<std::size_t>(bySize.size(), kSeedMarkers));
  std::vector<Pose> seeds;
  for (const Detection* d : bySize) {
    const LayoutMarker& m = *layout.find(d->id);
    // Unpolished: every seed is scored over all corners and the two kept are polished there.
    // SQPNP (5x IPPE's cost) only on the largest marker: it is there for IPPE's failure on an
    // exactly head-on square, and the largest marker's seed covers that.
    const PoseCandidates c =
        used.size() > 1 ? markerPoseSeeds(d->corners, m.edge(), calibration, d == bySize.front())
                        : PoseCandidates{};
    const Pose bodyInMarker = m.inBody().inverse();
    for (int i = 0; i < c.count; ++i) {
      const Pose s = c.poses[std::size_t(i)] * bodyInMarker;
      const bool repeat = std::any_of(seeds.begin(), seeds.end(), [&](const Pose& o) {
        return rotationAngle(o.R, s.R) < kSameSeedAngle && (o.t - s.t).norm() < 0.01 * s.t.norm();
      });
      if (!repeat) seeds.push_back(s);
    }
  }
  std::vector<std::pair<double, Pose>> scored;
  if (used.size() > 1) {
    // Every seed scored as it is over all corners; the best and its best turned-away rival
    // polished (the other seeds are near one of the two, or worse than both).
    std::vector<std::pair<double, Pose>> raw;
    for (const Pose& p : seeds) {
      const double e = reprojectionRms(all, calibration, p);
      if (std::isfinite(e)) raw.emplace_back(e, p);
    }
    std::stable_sort(raw.begin(), raw.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (i > 0 && rotationAngle(raw[i].second.R, raw[0].second.R) <= kFlipAngle) continue;
      Pose p = raw[i].second;
      const double e = polish(all, calibration, p);
      if (std::isfinite(e)) scored.emplace_back(e, p);
      if (i > 0) break;
    }
  }
  if (used.size() == 1) {
    // One marker: its own polished candidates and their errors are the answer.
    const LayoutMarker& m = *layout.find(used[0]->id);
    const PoseCandidates c =
        solveMarkerPose(used[0]->corners, m.edge(), calibration, PosePolish::kOwn);
    scored.clear();
    const Pose bodyInMarker = m.inBody().inverse();
    for (int i = 0; i < c.count; ++i)
      scored.emplace_back(c.rms[std::size_t(i)], c.poses[std::size_t(i)] * bodyInMarker);
  }
  if (scored.empty()) {
    out.note += (out.note.empty() ? "" : "; ") + std::string("the pose solver gave no finite pose");
    return out;
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::size_t pick = 0, alt = scored.size();
  for (std::size_t i = 1; i < scored.size(); ++i)
    if (rotationAngle(scored[i].second.R, scored[0].second.R) > kFlipAngle) {
      alt = i;
      break;
    }
  out.ratio = alt < scored.size() ? scored[alt].first / std::max(scored[0].first, 1e-12)
                                  : std::numeric_limits<double>::infinity();
  if (out.ratio < ambiguityRatio) {
    // Ambiguous: the candidate that explains which other markers were not read, else the one
    // nearer the previous pose.
    const int missedBest = unreadButVisible(layout, scored[0].second, used, calibration);
    const int missedAlt = unreadButVisible(layout, scored[alt].second, used, calibration);
    if (missedBest != missedAlt) {
      out.byVisibility = true;
      if (missedAlt < missedBest) pick = alt;
    } else if (previous) {
      out.byContinuity = true;
      if (rotationAngle(scored[alt].second.R, previous->R) <
          rotationAngle(scored[0].second.R, previous->R))
        pick = alt;
    }
  }
  out.valid = true;
  out.pose = scored[pick].second;
  out.rms = scored[pick].first;
  for (const Detection* d : used) out.ids.push_back(d->id);
  return out;
}

std::vector<std::array<cv::Point2d, 4>> projectLayout(const MarkerLayout& layout, const Pose& body,
                                                      const CameraCalibration& calibration) {
  std::vector<cv::Point3d> cam;
  for (const auto& m : layout.markers)
    for (const auto& c : m.corners) {
      const Eigen::Vector3d x = body.apply(c);
      cam.emplace_back(x.x(), x.y(), x.z());
    }
  std::vector<cv::Point2d> px;
  cv::projectPoints(cam, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(calibration.K),
                    calibration.distortion, px);
  std::vector<std::array<cv::Point2d, 4>> out(layout.markers.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    for (std::size_t k = 0; k < 4; ++k) out[i][k] = px[4 * i + k];
  return out;
}

}  // namespace ps::tracking
