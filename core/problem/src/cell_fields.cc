#include "vtb/problem/cell_fields.hh"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace vtb {

template <int dim> void cell_max_principal_strain(const Mesh<dim>& mesh, const Nodal<dim>& u, std::vector<float>& out) {
  out.resize(mesh.cells.size());
  for (std::size_t c = 0; c < mesh.cells.size(); ++c) {
    const auto& cell = mesh.cells[c];
    Mat<dim> Dm, Ds;
    for (int k = 0; k < dim; ++k) {
      const int v = cell[static_cast<std::size_t>(k) + 1];
      Dm.col(k) = mesh.points.col(v) - mesh.points.col(cell[0]);
      Ds.col(k) = Dm.col(k) + u.col(v) - u.col(cell[0]);
    }
    const Mat<dim> F = Ds * Dm.inverse();
    const Mat<dim> E = 0.5 * (F.transpose() * F - Mat<dim>::Identity());
    const Vec<dim> ev = Eigen::SelfAdjointEigenSolver<Mat<dim>>(E, Eigen::EigenvaluesOnly).eigenvalues();
    const double m = std::max(std::abs(ev.minCoeff()), std::abs(ev.maxCoeff()));
    out[c] = std::isfinite(m) ? static_cast<float>(m) : std::numeric_limits<float>::infinity();
  }
}

template <int dim> double max_small_strain(const Mesh<dim>& mesh, const Nodal<dim>& u) {
  double worst = 0;
  for (const auto& cell : mesh.cells) {
    Mat<dim> Dm, Du;
    for (int k = 0; k < dim; ++k) {
      const int v = cell[static_cast<std::size_t>(k) + 1];
      Dm.col(k) = mesh.points.col(v) - mesh.points.col(cell[0]);
      Du.col(k) = u.col(v) - u.col(cell[0]);
    }
    const Mat<dim> g = Du * Dm.inverse();
    const Mat<dim> eps = 0.5 * (g + g.transpose());
    // The closed form (computeDirect), several times cheaper than the iterative QR: the largest
    // |eigenvalue| is ||eps||'s to round-off of ||eps|| either way (tested against the QR).
    Eigen::SelfAdjointEigenSolver<Mat<dim>> es;
    const double m = es.computeDirect(eps, Eigen::EigenvaluesOnly).eigenvalues().cwiseAbs().maxCoeff();
    if (!(m <= worst)) worst = m; // propagates NaN
  }
  return worst;
}

namespace {

/// The closest proper rotation to F by its SVD (an inverted cell's included: det R = +1).
template <int dim> Mat<dim> svd_rotation(const Mat<dim>& F) {
  const Eigen::JacobiSVD<Mat<dim>> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat<dim> U = svd.matrixU();
  if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(dim - 1) *= -1;
  return U * svd.matrixV().transpose();
}

/// The angle of F's polar rotation R (F = R S, S symmetric positive definite) where det F > 0:
/// in 2D in closed form, R's (cos, sin) along (F00 + F11, F10 - F01); in 3D by Newton's iteration
/// X <- (X + X^-T) / 2 from F (Higham), quadratic near R: 4-6 iterations, far cheaper than a
/// JacobiSVD per cell at every sample. The angle is atan2 of R's axial
/// vector's length and (tr R - 1) / 2 (acos of the trace alone loses half the digits near 0).
/// An inverted cell, or an iteration that does not settle, takes the SVD's closest rotation.
template <int dim> double rotation_angle(const Mat<dim>& F) {
  if constexpr (dim == 2) {
    if (F.determinant() > 0) return std::abs(std::atan2(F(1, 0) - F(0, 1), F(0, 0) + F(1, 1)));
    const Mat<2> R = svd_rotation<2>(F);
    return std::abs(std::atan2(R(1, 0), R(0, 0)));
  } else {
    Mat<3> R = F;
    bool settled = false;
    if (F.determinant() > 0)
      for (int k = 0; k < 30 && !settled; ++k) {
        const Mat<3> next = 0.5 * (R + R.inverse().transpose());
        settled = (next - R).cwiseAbs().maxCoeff() <= 1e-12; // the error of `next`: ~1e-24, rounding
        R = next;
      }
    if (!settled) R = svd_rotation<3>(F);
    const Vec<3> axial(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
    return std::atan2(0.5 * axial.norm(), 0.5 * (R.trace() - 1));
  }
}

} // namespace

template <int dim> double max_rotation(const Mesh<dim>& mesh, const Nodal<dim>& u) {
  double worst = 0;
  for (const auto& cell : mesh.cells) {
    Mat<dim> Dm, Ds;
    for (int k = 0; k < dim; ++k) {
      const int v = cell[static_cast<std::size_t>(k) + 1];
      Dm.col(k) = mesh.points.col(v) - mesh.points.col(cell[0]);
      Ds.col(k) = Dm.col(k) + u.col(v) - u.col(cell[0]);
    }
    const Mat<dim> F = Ds * Dm.inverse();
    const double angle = F.allFinite() ? rotation_angle<dim>(F) : std::numeric_limits<double>::quiet_NaN();
    if (!(angle <= worst)) worst = angle; // propagates NaN
  }
  return worst;
}

std::string small_strain_regime_note(double rotation, double strain) {
  constexpr double kRotation = 0.1, kStrain = 0.01;
  if (rotation <= kRotation && strain <= kStrain) return "";
  std::ostringstream os;
  os << std::setprecision(3) << "the scene leaves the small-strain regime in which the linear FEM is a reference "
     << "(max rotation " << rotation << " rad, limit " << kRotation << "; max strain " << strain << ", limit "
     << kStrain << "): the kinematics the linear theory drops are about "
     << std::max(rotation * rotation / 2, strain / 2) * 100
     << " % of the displacement, beyond the reference's own 0.5 %; differences of that size are the kinematics, "
        "not the springs (docs/fem.md)";
  return os.str();
}

std::string large_strain_run_note(double rotation, double strain, bool load_checked) {
  if (small_strain_regime_note(rotation, strain).empty()) return "";
  std::ostringstream os;
  os << std::setprecision(3) << "the run leaves the small-strain regime (max strain " << strain << ", max rotation "
     << rotation << " rad; limits 0.01 and 0.1 rad): "
     << (load_checked ? "its load check above is a linear one (static, small strain), so it does not measure this "
                        "run; "
                      : "")
     << "the reference at these strains is the neo-Hookean FEM (vtb compare SCENE --kinematics neo-hookean, "
        "docs/fem.md)";
  return os.str();
}

template void cell_max_principal_strain<2>(const Mesh<2>&, const Nodal<2>&, std::vector<float>&);
template void cell_max_principal_strain<3>(const Mesh<3>&, const Nodal<3>&, std::vector<float>&);
template double max_small_strain<2>(const Mesh<2>&, const Nodal<2>&);
template double max_small_strain<3>(const Mesh<3>&, const Nodal<3>&);
template double max_rotation<2>(const Mesh<2>&, const Nodal<2>&);
template double max_rotation<3>(const Mesh<3>&, const Nodal<3>&);

} // namespace vtb
