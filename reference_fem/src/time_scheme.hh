#pragma once
// Internal to reference_fem: the time schemes of M a + C v + K u = f that the serial and the
// distributed solvers share, written once for any deal.II vector and matrix types.
//   generalized-alpha (Chung-Hulbert, rho_inf = 0: am = -1, af = 0, gamma = 3/2, beta = 1),
//   newmark (average acceleration: beta = 1/4, gamma = 1/2), backward-euler, and the static solve.

#include <string>

namespace vtb::fem {

struct TimeScheme {
  double dt = 0;
  bool is_static = false, newmark_family = false;
  bool static_path = false; ///< static: the equilibrium at every sample time, not once at the end
  double am = 0, af = 0, beta = 0.25, gamma = 0.5; ///< Newmark-family weights

  TimeScheme(const std::string& scheme, bool static_solve, double step, bool path = false)
      : dt(step), is_static(static_solve), static_path(static_solve && path) {
    newmark_family = !static_solve && scheme != "backward-euler";
    if (scheme == "generalized-alpha") {
      const double rho = 0.0; // spectral radius at infinite frequency: full high-frequency damping
      am = (2 * rho - 1) / (rho + 1);
      af = rho / (rho + 1);
      gamma = 0.5 - am + af;
      beta = 0.25 * (1 - am + af) * (1 - am + af);
    }
  }

  /// The step matrix A = ck K + cm M + cc C.
  double ck() const { return newmark_family ? 1 - af : 1.0; }
  double cm() const { return newmark_family ? (1 - am) / (beta * dt * dt) : is_static ? 0.0 : 1 / (dt * dt); }
  double cc() const { return newmark_family ? (1 - af) * gamma / (beta * dt) : is_static ? 0.0 : 1 / dt; }
  /// When the loads of the step to t_new are evaluated.
  double load_time(double t_new) const { return newmark_family ? t_new - af * dt : t_new; }

  /// Adds the history of (u, v, a) to rhs, which holds f(load_time) on entry, so that
  /// A u+ = rhs. Newmark family: d_a = -(u + dt v + dt^2 (1/2 - beta) a) / (beta dt^2),
  /// d_v = v + dt (1 - gamma) a + gamma dt d_a (kept for update()), and
  /// rhs -= am M a + (1 - am) M d_a + af C v + (1 - af) C d_v + af K u.
  /// Backward Euler: rhs += M (u / dt^2 + v / dt) + C u / dt. Static: nothing.
  template <class Vec, class Mat>
  void add_history(const Mat& M, const Mat& C, const Mat& K, const Vec& u, const Vec& v, const Vec& a, Vec& da, Vec& dv,
                   Vec& tmp, Vec& rhs) const {
    if (newmark_family) {
      da = u;
      da.add(dt, v, dt * dt * (0.5 - beta), a);
      da *= -1 / (beta * dt * dt);
      dv = v;
      dv.add(dt * (1 - gamma), a, gamma * dt, da);
      tmp = a;
      tmp *= -am;
      tmp.add(-(1 - am), da);
      M.vmult_add(rhs, tmp);
      tmp = v;
      tmp *= -af;
      tmp.add(-(1 - af), dv);
      C.vmult_add(rhs, tmp);
      if (af != 0) { // generalized-alpha at rho_inf = 0 has af = 0: no product with K
        tmp = u;
        tmp *= -af;
        K.vmult_add(rhs, tmp);
      }
    } else if (!is_static) {
      tmp = u;
      tmp *= 1 / (dt * dt);
      tmp.add(1 / dt, v);
      M.vmult_add(rhs, tmp);
      tmp = u;
      tmp *= 1 / dt;
      C.vmult_add(rhs, tmp);
    }
  }

  /// The new velocity and acceleration of one free dof from its new displacement: Newmark
  /// family a+ = u+ / (beta dt^2) + d_a, v+ = gamma u+ / (beta dt) + d_v; backward Euler
  /// v+ = (u+ - u) / dt, a+ = (v+ - v) / dt. (Static: unchanged.)
  void update(double u_new, double u_old, double da, double dv, double& v, double& a) const {
    if (newmark_family) {
      const double c1 = 1 / (beta * dt * dt), c2 = gamma / (beta * dt);
      a = c1 * u_new + da;
      v = c2 * u_new + dv;
    } else if (!is_static) {
      const double v_new = (u_new - u_old) / dt;
      a = (v_new - v) / dt;
      v = v_new;
    }
  }
};

} // namespace vtb::fem
