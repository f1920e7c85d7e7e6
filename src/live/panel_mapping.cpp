#include "live/panel_mapping.hpp"

#include "sand/material.hpp"

namespace ps::live {

PanelSettings panelFrom(const LiveSettings& s) {
  PanelSettings p;
  const auto& o = s.options;
  p.displace = o.tool != replay::ReplayTool::kBrush;
  p.tinSand = o.tool == replay::ReplayTool::kTinSand;
  p.brushRadiusKm = float(o.brush.radius / 1e3);
  p.strengthM = float(o.brush.strength);
  p.sigma = float(o.brush.sigma);
  p.lower = o.brush.mode == edit::BrushMode::kLower;
  p.displaceRadiusKm = float(o.displace.radius / 1e3);
  p.pressM = float(o.pressDepth);
  p.material = o.displace.material.name;
  p.distMaxPx = float(s.distMaxPx);
  p.triangleBudget = int(s.triangleBudget);
  p.planetSizeCm = float(o.scene.planetRadius * 100);
  p.boardShadow = s.boardShadow;
  p.atmosphere = s.atmosphere;
  p.handMask = s.handMask;
  return p;
}

bool sculptingChanged(const PanelSettings& a, const PanelSettings& b) {
  return a.displace != b.displace || a.tinSand != b.tinSand || a.brushRadiusKm != b.brushRadiusKm ||
         a.strengthM != b.strengthM || a.sigma != b.sigma || a.lower != b.lower ||
         a.displaceRadiusKm != b.displaceRadiusKm || a.pressM != b.pressM ||
         a.material != b.material || a.spinDeg != b.spinDeg || a.tiltDeg != b.tiltDeg ||
         a.planetSizeCm != b.planetSizeCm;
}

replay::SessionSettings panelTarget(const PanelSettings& p, const PanelSettings& applied,
                                    const replay::SessionSettings& now) {
  replay::SessionSettings t = now;
  t.tool = !p.displace ? replay::ReplayTool::kBrush
           : p.tinSand ? replay::ReplayTool::kTinSand
                       : replay::ReplayTool::kDisplace;
  t.brush.radius = p.brushRadiusKm * 1e3;
  t.brush.strength = p.strengthM;
  t.brush.sigma = p.sigma;
  if (p.lower != applied.lower)
    t.brush.mode = p.lower ? edit::BrushMode::kLower : edit::BrushMode::kRaise;
  t.displace.radius = p.displaceRadiusKm * 1e3;
  t.pressDepth = p.pressM;
  if (p.material != now.displace.material.name)
    t.displace.material = sand::Material::preset(p.material);
  t.spinDeg = p.spinDeg;
  t.tiltDeg = p.tiltDeg;
  t.planetRadius = double(p.planetSizeCm) / 100;
  return t;
}

}  // namespace ps::live
