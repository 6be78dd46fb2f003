#pragma once
/// \file
/// The contact's local model that the physics hands the servo with each publish (multirate
/// rendering: Cavusoglu and Tendick 2000; the contact compliance of Saupin, Duriez and Cotin
/// 2008). Between two physics steps the servo does not wait for the body: it solves the virtual
/// coupling against a linear model of the body at the contact,
///
///   p(f) = p_free(t) + C (f - g),
///
/// the tip's proxy p as a function of the force f on the body: p_free(t) is the free motion
/// (the published nodes moved on with their velocities, which the contact search reads), g the
/// force the physics applied over the step it published (its state already answers g), and C
/// the footprint's compliance over one physics step (dim x dim, m/N): dt^2 w^T H^-1 w of the
/// solver's own system (Integrator::coupling_compliance), or where the solver has none the
/// half-space's under the tip. With the coupling F = k (p - h) + b (v_p - v_h) on the handle and
/// f = -F on the body, the force solves
///
///   (I + k C) F = F_free - k C g,
///
/// F_free being the coupling against the free motion alone. F = -g is its fixed point, so a held
/// press renders the physics' own equilibrium whatever C; between publishes the force follows
/// the hand with the coupling in series with the body's local compliance, not the coupling
/// alone. Contact pushes: a negative normal part is dropped, as virtual_coupling does.
///
/// The other way, a physics step takes from the servo's cycles since the last publish the force
/// of the coupling spring anchored where the servo held it (applied_force). Pure and
/// allocation-free (fixed-size Eigen).

#include "vtb/haptics/contact_result.hh"

#include <Eigen/Core>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace vtb {

template <int dim> struct LocalModel {
  using Vec = Eigen::Matrix<double, dim, 1>;
  using Mat = Eigen::Matrix<double, dim, dim>;
  bool valid = false;           ///< the physics coupled this probe in its last step
  Mat compliance = Mat::Zero(); ///< C, m/N
  Vec applied = Vec::Zero();    ///< g, N: the force on the body over the published step
};

/// The coupling force on the handle solved against the local model: (I + k C) F = F_free - k C g,
/// then its pull along `depth` (proxy - handle) dropped. k: the coupling's stiffness (in series
/// with the tip's missing compliance, tip_stiffness). An invalid model returns F_free.
template <int dim>
Eigen::Matrix<double, dim, 1> solve_against_local_model(const Eigen::Matrix<double, dim, 1>& free_force,
                                                        const Eigen::Matrix<double, dim, 1>& depth, double k,
                                                        const LocalModel<dim>& m) {
  using Vec = Eigen::Matrix<double, dim, 1>;
  using Mat = Eigen::Matrix<double, dim, dim>;
  if (!m.valid) return free_force;
  const Mat a = Mat::Identity() + k * m.compliance;
  Vec f = a.partialPivLu().solve(free_force - k * (m.compliance * m.applied));
  if (!f.allFinite()) return free_force;
  const double d2 = depth.squaredNorm();
  if (d2 > 0) {
    const double normal = f.dot(depth) / d2;
    if (normal < 0) f -= normal * depth;
  }
  return f;
}

/// What a probe's servo did since it last saw a new snapshot: over `cycles` servo cycles, the
/// forces on the body it applied and where its local model put the proxy, summed, and the last
/// footprint it touched (count 0: none), where a contact that ended before the step's end left
/// its force (ended_contact_force).
template <int dim> struct ForceHistory {
  using Vec = Eigen::Matrix<double, dim, 1>;
  Vec sum = Vec::Zero(), proxy_sum = Vec::Zero();
  long cycles = 0;
  Footprint touched;
};

/// The force a physics step takes from the servo's cycles, at the footprint's position `proxy`
/// (w . x) at the step's start, for a coupling of stiffness k that the step solves implicitly
/// (its -k (p_end - p_start) is the step's own): the spring from the proxy to the anchor the
/// servo's mean force held, a = p_mean + f_mean / k, with p_mean where the servo's local model
/// put the proxy,
///
///   f = f_mean + k (p_mean - proxy).
///
/// Anchored at the physics' own proxy instead (f_mean alone), the body's motion since the servo
/// saw it came back to it a step late, and a soft block under a stiff coupling rang at a 22 ms
/// step. The hand's motion is not predicted: moved on with the handle's velocity to the step's
/// end, the force took the device's 18 Hz handle mode with it and the 2D press rang at 40 ms.
/// A force that would pull is none.
template <int dim>
Eigen::Matrix<double, dim, 1> applied_force(const ForceHistory<dim>& h, const Eigen::Matrix<double, dim, 1>& proxy,
                                            double k) {
  using Vec = Eigen::Matrix<double, dim, 1>;
  if (h.cycles <= 0) return Vec::Zero();
  const double n = static_cast<double>(h.cycles);
  const Vec mean = h.sum / n;
  const Vec f = mean + k * (h.proxy_sum / n - proxy);
  return f.dot(mean) > 0 ? f : Vec::Zero();
}

/// The force a physics step takes from a contact that ended among the servo's cycles since the
/// last publish: the mean of the forces the cycles applied (0 for those out of contact), so
/// that the body receives the impulse the user gave it, on the last footprint touched and as a
/// force alone (the coupling no longer holds the body at the step's end).
template <int dim> Eigen::Matrix<double, dim, 1> ended_contact_force(const ForceHistory<dim>& h) {
  return h.cycles > 0 ? Eigen::Matrix<double, dim, 1>(h.sum / static_cast<double>(h.cycles))
                      : Eigen::Matrix<double, dim, 1>::Zero();
}

/// The half-space's mean compliance under a uniform disc of radius r (3D), isotropic: what the
/// servo solves against where the physics' solver does not solve its contact (m/N); 0 where it
/// has no finite value (a point proxy, 2D).
inline double half_space_tip_compliance(int dim, double young_modulus, double poisson_ratio, double radius) {
  if (dim != 3 || !(radius > 0) || !(young_modulus > 0)) return 0.0;
  return 16.0 * (1.0 - poisson_ratio * poisson_ratio) / (3.0 * M_PI * M_PI * young_modulus * radius);
}

} // namespace vtb
