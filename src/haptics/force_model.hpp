#pragma once
// The force law of paper 004 with the safety layer around it, one tick at a time. Everything is
// in device space (docs/HAPTICS.md): positions in metres, forces in newtons. No allocation, no
// locks: ForceModel::tick is what the 1 kHz thread runs after it has read the device and probed
// the terrain snapshot.
#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "haptics/settings.hpp"

namespace ps::haptics {

// Why a tick gave zero force.
enum class Fault : std::uint8_t {
  kNone = 0,
  kDeviceLost,  // the device did not answer (or its sample is stale)
  kNonFinite,   // NaN/inf position or time
  kJump,        // the tool moved farther between ticks than maxSpeed allows
  kTimeOrder,   // time did not advance
  kNoTerrain,   // no terrain snapshot under the tool (none published yet, or tool outside it)
};
const char* toString(Fault f);
Fault faultFromString(const std::string& s);  // InputError naming the choices

// The stiffness- and force-clamped repulse law: F(d) = integral_0^d min(k_s k_c e^{k_c x}, K) dx,
// capped at maxForce. Equal to k_s (e^{k_c d} - 1) while its slope is below K, linear with slope
// K beyond; 0 for d <= 0 (and for NaN). Never above the paper's law, slope never above K.
class RepulseLaw {
 public:
  RepulseLaw(const ForceConstants& c, const DeviceLimits& limits);
  double operator()(double depth) const;
  // Depth where the exponential's slope reaches maxStiffness (<= 0: linear from the surface).
  double kneeDepth() const { return knee_; }

 private:
  double ks_, kc_, stiffness_, maxForce_, knee_, kneeForce_;
};

// The terrain under the tool, as the loop found it in its snapshot (device space).
struct Contact {
  bool valid = false;  // false: no terrain there (zero force, Fault::kNoTerrain)
  double depth = 0;    // below the surface along `normal` (m, device space); <= 0 above
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // outward radial direction, unit
};

struct TickInput {
  double time = 0;                                     // s, strictly increasing
  bool deviceOk = true;                                // the device answered with a fresh sample
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // tool tip, device frame (m)
  Contact contact;
};

struct TickOutput {
  double time = 0;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();     // to command (N, device frame)
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // filtered (m/s)
  double depth = 0;                                    // m (device space); 0 when not valid
  double repulse = 0;                                  // |F_r| before the ramp (N)
  double damping = 0;                                  // min(k_f |F_r|, maxDamping) (N s/m)
  double ramp = 0;                                     // [0, 1]
  bool touching = false;
  bool slewLimited = false;  // the growth limit cut this tick's force
  Fault fault = Fault::kNone;
};

// Per-tick state: velocity filter, ramp, last force. Faults give exactly zero force, reset the
// filter and restart the ramp; a jump takes the new position as the new reference.
class ForceModel {
 public:
  explicit ForceModel(const HapticSettings& settings);  // validates

  TickOutput tick(const TickInput& in);
  void reset();  // as at start: ramp 0, no reference position

  const HapticSettings& settings() const { return settings_; }
  const RepulseLaw& law() const { return law_; }
  std::uint64_t faults() const { return faults_; }

 private:
  TickOutput zero(const TickInput& in, Fault f);

  HapticSettings settings_;
  RepulseLaw law_;
  double dtNominal_;
  bool have_ = false;
  double lastTime_ = 0;
  Eigen::Vector3d lastPos_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d vel_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d lastForce_ = Eigen::Vector3d::Zero();
  double ramp_ = 0;
  std::uint64_t faults_ = 0;
};

}  // namespace ps::haptics
