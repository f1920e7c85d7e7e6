// Marker corners refined by aligning the marker's canonical image (corner_refine.hpp), against
// markers drawn with exactly known corners, blurred and noisy as a camera gives them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <tuple>

#include "median.hpp"
#include "tracking/corner_refine.hpp"
#include "tracking/detector.hpp"
#include "tracking/marker_family.hpp"
#include "tracking/textured_quad.hpp"

using namespace ps;

namespace {

using Quad = std::array<cv::Point2d, 4>;

// A tag36h11 marker on a white card one cell wider than its border all round (a tool cube's
// face), drawn on a grey background with its border's corners at `corners`, then blurred and
// given noise.
cv::Mat drawFace(int id, const Quad& corners, double blur, double noise, std::mt19937& rng) {
  cv::Mat image(240, 320, CV_8U, cv::Scalar(90));
  const auto info = tracking::familyInfo("tag36h11");
  const cv::Mat cells = tracking::markerCells("tag36h11", id);
  const double a = info.edgeOffset, b = info.edgeOffset + info.edgeCells;
  const std::vector<cv::Point2f> src = {
      {float(a), float(a)}, {float(b), float(a)}, {float(b), float(b)}, {float(a), float(b)}};
  std::vector<cv::Point2f> dst;
  for (const auto& c : corners) dst.emplace_back(float(c.x), float(c.y));
  tracking::drawTexturedQuad(image, cells, cv::getPerspectiveTransform(src, dst), 8);
  cv::Mat f;
  image.convertTo(f, CV_32F);
  if (blur > 0) cv::GaussianBlur(f, f, {0, 0}, blur);
  std::normal_distribution<float> n(0.0f, float(noise));
  for (auto it = f.begin<float>(); it != f.end<float>(); ++it) *it += n(rng);
  f.convertTo(image, CV_8U);
  return image;
}

// A face about `side` px wide near the image's centre, turned in the image and tilted out of
// it by up to `tiltDeg` (a perspective squash of one pair of edges against the other).
Quad randomFace(std::mt19937& rng, double side, double tiltDeg) {
  std::uniform_real_distribution<double> u(-1, 1);
  const cv::Point2d c(160 + 20 * u(rng), 120 + 20 * u(rng));
  const double turn = M_PI * u(rng), half = 0.5 * side * (1 + 0.1 * u(rng));
  const double squash = std::sin(tiltDeg * M_PI / 180 * u(rng)) * 0.08;  // edge length ratio
  const cv::Point2d ax(std::cos(turn), std::sin(turn)), ay(-ax.y, ax.x);
  const double s[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  Quad q;
  for (std::size_t k = 0; k < 4; ++k) {
    const double w = 1 + squash * s[k][1];  // the far edge shorter than the near one
    q[k] = c + half * (w * s[k][0] * ax + s[k][1] * ay);
  }
  return q;
}

double maxError(const Quad& a, const Quad& b) {
  double e = 0;
  for (std::size_t k = 0; k < 4; ++k) e = std::max(e, cv::norm(a[k] - b[k]));
  return e;
}

using testkit::median;

}  // namespace

// Random faces 40-60 px across, near head-on, blurred and noisy. With the synthetic scenes'
// camera (blur 0.4 px, noise 1.5 levels) AprilTag's full-resolution edge fit leaves its corners
// about 0.085 px off (median of the worst corner) and the alignment 0.02 px: required, at least
// twice as close. Blurred twice as much the edge fit does better and the alignment worse
// (0.057 and 0.037 px): required, still closer.
TEST(TrackingCornerRefine, AlignedCornersBeatTheEdgeFitOnRandomFaces) {
  std::mt19937 rng(7);
  tracking::DetectorConfig config;
  config.decimate = 1.0;
  config.regions = false;
  auto detector = tracking::makeDetector(config);
  std::uniform_real_distribution<double> side(40, 60);
  for (const auto& [blur, noise, ratio] : {std::tuple{0.4, 1.5, 0.5}, std::tuple{0.8, 2.0, 1.0}}) {
    std::vector<double> detected, refined;
    for (int trial = 0; trial < 40; ++trial) {
      const Quad truth = randomFace(rng, side(rng), 6);
      const cv::Mat image = drawFace(20 + trial % 5, truth, blur, noise, rng);
      const auto found = detector->detect(image);
      ASSERT_EQ(found.size(), 1u) << "trial " << trial;
      tracking::Detection d = found[0];
      detected.push_back(maxError(d.corners, truth));
      ASSERT_TRUE(tracking::refineCornersByTemplate(image, "tag36h11", d)) << "trial " << trial;
      refined.push_back(maxError(d.corners, truth));
    }
    EXPECT_LT(median(refined), ratio * median(detected))
        << "blur " << blur << ": median worst corner refined " << median(refined)
        << " px, detected " << median(detected) << " px";
    EXPECT_LT(*std::max_element(refined.begin(), refined.end()), 0.1) << "blur " << blur;
  }
}

// What cannot be matched is left as the detector gave it: corners far from the marker, a marker
// at the image's border, one too small for the template, an image without the marker.
TEST(TrackingCornerRefine, LeavesCornersAloneWhereNothingMatches) {
  std::mt19937 rng(11);
  const Quad truth = randomFace(rng, 50, 0);
  const cv::Mat image = drawFace(21, truth, 0.8, 2.0, rng);
  tracking::Detection d;
  d.id = 21;
  // Corners 8 px off: the alignment finds nothing there, or the marker further than allowed.
  Quad off = truth;
  for (auto& c : off) c += cv::Point2d(6, -5);
  d.corners = off;
  EXPECT_FALSE(tracking::refineCornersByTemplate(image, "tag36h11", d));
  EXPECT_EQ(d.corners, off);
  // Too near the border for the quiet zone.
  Quad edge;
  for (std::size_t k = 0; k < 4; ++k) edge[k] = truth[k] - truth[0] + cv::Point2d(1, 1);
  d.corners = edge;
  EXPECT_FALSE(tracking::refineCornersByTemplate(image, "tag36h11", d));
  EXPECT_EQ(d.corners, edge);
  // Fewer pixels a cell than the template has (28 px across: 3.5 px a cell against 4).
  const Quad small = randomFace(rng, 28, 0);
  const cv::Mat smallImage = drawFace(22, small, 0.4, 1.5, rng);
  d.id = 22;
  d.corners = small;
  EXPECT_FALSE(tracking::refineCornersByTemplate(smallImage, "tag36h11", d));
  EXPECT_EQ(d.corners, small);
  d.id = 21;
  // Flat grey where the marker should be.
  const cv::Mat flat(240, 320, CV_8U, cv::Scalar(128));
  d.corners = truth;
  EXPECT_FALSE(tracking::refineCornersByTemplate(flat, "tag36h11", d));
  EXPECT_EQ(d.corners, truth);
}

// In video (the region detector), the refinement touches only a rigid set's lone marker: a
// marker outside every set, and a set's markers when two are seen, come out bit for bit as the
// detector found them.
TEST(TrackingCornerRefine, OnlyALoneMarkerOfARigidSetIsRefined) {
  std::mt19937 rng(13);
  const Quad lone = randomFace(rng, 50, 4);
  Quad single = lone, pairA = lone, pairB = lone;
  for (std::size_t k = 0; k < 4; ++k) {
    single[k] += cv::Point2d(-90, -70);
    pairA[k] += cv::Point2d(90, -70);
    pairB[k] += cv::Point2d(90, 60);
  }
  cv::Mat image = drawFace(20, lone, 0.8, 2.0, rng);
  cv::Mat more = drawFace(5, single, 0.8, 0.0, rng);
  cv::Mat pair1 = drawFace(30, pairA, 0.8, 0.0, rng), pair2 = drawFace(31, pairB, 0.8, 0.0, rng);
  // Paste the other markers' neighbourhoods into the lone one's image.
  for (const auto& [src, q] :
       {std::pair{more, single}, std::pair{pair1, pairA}, std::pair{pair2, pairB}}) {
    const cv::Rect r =
        cv::boundingRect(std::vector<cv::Point2f>(
            {cv::Point2f(q[0]), cv::Point2f(q[1]), cv::Point2f(q[2]), cv::Point2f(q[3])})) +
        cv::Size(16, 16) - cv::Point(8, 8);
    src(r).copyTo(image(r));
  }
  auto run = [&](bool refine) {
    tracking::DetectorConfig config;
    config.ids = {5, 20, 21, 30, 31};
    config.sets = {{20, 21}, {30, 31}};
    config.refineLoneSetMarkers = refine;
    return tracking::makeDetector(config)->detect(image);
  };
  const auto plain = run(false), refined = run(true);
  ASSERT_EQ(plain.size(), 4u);
  ASSERT_EQ(refined.size(), 4u);
  for (std::size_t i = 0; i < plain.size(); ++i) {
    ASSERT_EQ(plain[i].id, refined[i].id);
    if (plain[i].id == 20) {
      EXPECT_NE(plain[i].corners, refined[i].corners);
      EXPECT_LT(maxError(refined[i].corners, lone), maxError(plain[i].corners, lone));
    } else {
      EXPECT_EQ(plain[i].corners, refined[i].corners) << "id " << plain[i].id;
    }
  }
}
