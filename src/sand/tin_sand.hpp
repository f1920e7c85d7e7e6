#pragma once
// Sand on a triangulated irregular network (paper 000): the surface is a constrained Delaunay
// triangulation whose vertices carry heights (tin::DynamicTin), and Section 4's loop runs on it:
//   1. stamping: a tool's outer contour (heights from the terrain) is constrained first, then
//      its inner contour (pressed to the tool's bottom), the terrain inside pressed down,
//      redundant inner vertices removed; constrained edges carry their stamp's generation, and
//      older ones inside a new stamp are freed. What the tool pressed out is pushed aside onto
//      a rampart around it (paper 004's displacement), so the volume is kept;
//   2. erosion along edges over the active list Le: a vertex gives material to each lower
//      neighbour whose edge is steeper than the material's talus (critical) angle;
//   3. redundant vertices (every edge within flatDeg of the horizontal), found through the list
//      Lr, are removed and the hole re-filled (tin::DynamicTin::remove, which puts back the
//      volume the new triangles change).
// Volume: tin::DynamicTin's V (the integral of the surface above the plane h = 0). Erosion moves
// volume between vertices in the units of their weights (exact but for rounding); stamping puts
// on the rampart exactly the volume the stamp changed (measured over the whole TIN before and
// after, O(n) per stamp); removal puts back what the re-filled hole changed.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "sand/material.hpp"
#include "tin/dynamic_tin.hpp"

namespace ps::sand {

// A tool's imprint: its outline is the inner contour (pressed to the tool's bottom),
// counter-clockwise around the tool's centre (the origin), and seen whole from it (star-shaped:
// every edge turns counter-clockwise about the origin). The outer contour is the outline moved
// out by `rim` along each point's ray (the paper keeps the two a small distance apart: a TIN
// cannot hold a vertical wall).
struct TinStampTool {
  std::vector<Eigen::Vector2d> outline;  // metres, relative to the centre
  double rim = 0;                        // metres, > 0
  double rampartWidth = 0;               // metres beyond the outer contour, > 0
  // Whether what the tool presses out goes onto a rampart (the volume kept). Off: a press only,
  // the surface left is the tool's shape and no more (the volume is not kept; bench sand-tin's
  // exact-shape comparison, where the surface a stroke must leave is known exactly).
  bool pushAside = true;

  // A regular polygon of `segments` corners on a circle; rim 5 % and rampart 100 % of radius.
  static TinStampTool disc(double radius, int segments = 24);
  // Throws core::InputError naming what is wrong: fewer than 3 points, a point that is not
  // finite or repeats, edges that cross, an outline not seen whole from its centre (or turning
  // clockwise), rim or rampart not positive.
  void validate() const;
  double outerRadius() const;  // the farthest point of the outer contour from the centre
  double reach() const { return outerRadius() + rampartWidth; }
};

struct TinSandSettings {
  Material material = Material::sand();  // talusDeg (the critical angle), erosionRate, cohesion
  // theta_flat: a vertex whose every edge is within this of the horizontal is redundant. Paper
  // 000 uses 0.4; we read it as degrees (0.4 radians, 23 degrees, would flatten most slopes
  // under the 30-degree critical angle). (0, 10].
  double flatDeg = 0.4;
  // Erosion iterations without a transfer before a vertex leaves Le (the paper's "a few").
  int idleSteps = 2;
  // Whether the removal step runs (off: the TIN only grows).
  bool removeRedundant = true;
  void validate() const;
  bool operator==(const TinSandSettings&) const = default;
};

struct TinStampStats {
  std::size_t inserted = 0;          // contour and rampart vertices added
  std::size_t pressed = 0;           // vertices lowered to the tool's bottom
  std::size_t removedInside = 0;     // redundant inner vertices removed
  std::size_t removedWall = 0;       // older vertices on or above the tool's wall removed
  std::size_t freedConstraints = 0;  // older constrained edges inside the stamp
  double displacedVolume = 0;        // m^3 the stamp moved onto its rampart
};

class TinSand {
 public:
  using Vertex = tin::DynamicTin::Vertex;

  explicit TinSand(tin::DynamicTin tin, TinSandSettings settings = {});

  // One stamp, the tool's bottom at height `bottom`, centred at `centre`. Throws
  // core::InputError (the surface unchanged) for a bad tool or one that reaches outside the
  // TIN's domain.
  TinStampStats stamp(const Eigen::Vector2d& centre, double bottom, const TinStampTool& tool);
  // One erosion iteration over Le, in Le's order (each transfer seen by the next). Returns how
  // many vertices gave material.
  std::size_t erode();
  // The redundancy test over Lr and the removal of what it finds. Returns vertices removed.
  std::size_t removeRedundant();

  const tin::DynamicTin& tin() const { return tin_; }
  // A vertex at p with height h (the surface changes there; nothing joins Le): a caller that
  // adds detail before a stamp (the region TIN, at the grid's heights around it).
  Vertex insert(const Eigen::Vector2d& p, double h) { return tin_.insert(p, h); }
  const TinSandSettings& settings() const { return settings_; }
  std::size_t activeCount() const { return le_.size(); }
  std::uint32_t generation() const { return generation_; }

  // Milliseconds spent in each part (accumulated; Figure 7's parts).
  struct Timing {
    double stampMs = 0, erodeMs = 0, detectMs = 0, removeMs = 0;
  };
  const Timing& timing() const { return timing_; }

 private:
  // A stamp's steps, in order (tin_sand.cpp).
  struct StampContours;
  StampContours placeContours(const Eigen::Vector2d& centre, double bottom,
                              const TinStampTool& tool, TinStampStats& stats);
  Vertex placeContourPoint(const Eigen::Vector2d& p, double cap, double snap);
  void constrainAcrossFreed(Vertex from, Vertex to, double cap, const StampContours& c,
                            std::vector<Vertex>& path);
  std::vector<Vertex> pressInside(const StampContours& c, const std::vector<Vertex>& nearby,
                                  double bottom, TinStampStats& stats);
  void removeFlatInside(const StampContours& c, const std::vector<Vertex>& inside, double bottom,
                        TinStampStats& stats);
  void removeWallVertices(const StampContours& c, const std::vector<Vertex>& nearby,
                          const Eigen::Vector2d& centre, const TinStampTool& tool,
                          TinStampStats& stats);
  void pushAside(const StampContours& c, const Eigen::Vector2d& centre, const TinStampTool& tool,
                 double displaced);
  // Into Le (woken); also into Lr when its height changed.
  void activate(Vertex v, bool changed = true);
  void markFlatCandidate(Vertex v);
  bool isFlat(Vertex v);
  // tin_.weight(v), cached until the triangulation changes (erosion asks for it many times).
  double weight(Vertex v);

  tin::DynamicTin tin_;
  TinSandSettings settings_;
  double tanTalus_ = 0, tanFlat_ = 0;
  std::uint32_t generation_ = 0;
  std::vector<Vertex> le_, lr_;            // the paper's Le and Lr
  std::vector<std::uint8_t> inLe_, inLr_;  // by vertex number
  std::vector<std::uint8_t> idle_;         // iterations without a transfer, by vertex number
  std::vector<Vertex> scratch_, neighbours_;
  std::vector<tin::DynamicTin::Neighbour> ring_;
  std::vector<double> weight_;
  std::vector<std::uint64_t> weightEpoch_;  // epoch + 1 of each cached weight (0: none)
  Timing timing_;
};

}  // namespace ps::sand
