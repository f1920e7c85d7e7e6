#pragma once
// Parameters of the haptic force path (docs/HAPTICS.md). Every length and speed here is in the
// device's space (metres and m/s of the hand's motion), every force in newtons: the planet is
// mapped into that space by a WorkspaceMap (planet metres per device metre).
#include <Eigen/Core>
#include <string>

namespace ps::haptics {

// Paper 004's material constants (eq. 1-3): repulse F_r = k_s (e^{k_c d} - 1) out along the
// radial direction, drag F_f = -k_f v |F_r|.
struct ForceConstants {
  double ks = 1000.0;  // N
  double kc = 5.0;     // 1/m (device space)
  double kf = 100.0;   // s/m: drag coefficient per newton of repulse is k_f |F_r| (N s/m)

  // The paper states k_s = 10^3, k_c = 1/2, k_f = 10 for a sand box of <-1,1>^2 scene units
  // (tool sphere radius 0.01). `paperUnitM` is the device-space length that one scene unit maps
  // to; forces are taken as newtons and time as seconds. Then k_c' = k_c / L, k_f' = k_f / L.
  static ForceConstants fromPaper(double ks, double kc, double kf, double paperUnitM);
  // The paper's sand with one scene unit = 0.1 m (its box is a 20 cm square of the device's
  // workspace): k_s = 1000 N, k_c = 5 /m, k_f = 100 s/m.
  static ForceConstants paperSand() { return fromPaper(1e3, 0.5, 10.0, 0.1); }

  void validate() const;  // core::InputError naming the constant
  bool operator==(const ForceConstants&) const = default;
};

// What the device can render; a driver reports its own (defaults: a conservative desktop device,
// below the paper's Omega (12 N) and Phantom Desktop figures).
struct DeviceLimits {
  double maxForce = 8.0;         // N, |F| never exceeds it
  double maxStiffness = 2000.0;  // N/m, the slope dF/dd of the repulse law is capped here
  double maxDamping = 10.0;      // N s/m, the drag coefficient k_f |F_r| is capped here
  double maxForceRate = 4000.0;  // N/s, growth of |F| between ticks (release is immediate)

  void validate() const;
  bool operator==(const DeviceLimits&) const = default;
};

struct SafetySettings {
  // Forces ramp in linearly over this time after the loop starts and after any fault (device
  // lost, NaN, jump, no terrain), counted while the tool touches; 0 = no ramp. [0, 5] s.
  double rampTime = 0.05;
  // A move between ticks longer than maxSpeed * max(dt, 1/rate) is a jump (teleport, tracking
  // glitch): zero force, filters reset, ramp restarts. (0, 100] m/s.
  double maxSpeed = 3.0;
  // Velocity filter: first-order low-pass on the position difference, this cut-off. (0, rate/2].
  double velocityCutoffHz = 50.0;
  // A new terrain snapshot (the editor moved sand under the tool) changes the depth at once; the
  // difference is blended out over this time instead of felt as a step. [0, 1] s.
  double surfaceBlendTime = 0.03;

  void validate(double rateHz) const;
  bool operator==(const SafetySettings&) const = default;
};

struct HapticSettings {
  ForceConstants constants = ForceConstants::paperSand();
  DeviceLimits limits;
  SafetySettings safety;
  double rateHz = 1000.0;  // the loop's fixed rate, [100, 10000] Hz

  void validate() const;  // core::InputError naming the first bad parameter
  double period() const { return 1.0 / rateHz; }
};

// Device space -> planet frame: p_planet = origin + scale * rotation * p_device. Forces computed
// along planet directions are rotated back with rotation^T; lengths divide by scale.
struct WorkspaceMap {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // orthonormal
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();        // planet frame (planet metres)
  double scale = 1.0;  // planet metres per device metre, finite and > 0

  Eigen::Vector3d toPlanet(const Eigen::Vector3d& device) const {
    return origin + scale * (rotation * device);
  }
  Eigen::Vector3d toDevice(const Eigen::Vector3d& planet) const {
    return rotation.transpose() * (planet - origin) / scale;
  }
  void validate() const;
};

}  // namespace ps::haptics
