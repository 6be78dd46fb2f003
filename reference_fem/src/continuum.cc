// The continuum's static answer by a ladder of uniform refinements of P2 (continuum.hh).
#include "vtb/fem/continuum.hh"

#include "continuum_counts.hh"
#include "kelvin_voigt_problem.hh"
#include "vtb/fem/kelvin_voigt.hh"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace vtb::fem {

namespace {

std::string thousands(long n) {
  std::string s = std::to_string(n);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(static_cast<std::size_t>(i), ",");
  return s;
}

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g %%", 100 * x);
  return buf;
}

/// The P1 consistent mass of the mesh at unit density (times the thickness in 2D), per dof:
/// (rho t |T| / ((d+1)(d+2))) (1 + delta_ab) between the cell's nodes, on each component.
template <int dim> Eigen::SparseMatrix<double> p1_mass(const Mesh<dim>& mesh, double thickness) {
  std::vector<Eigen::Triplet<double>> t;
  for (const auto& cell : mesh.cells) {
    Eigen::Matrix<double, dim, dim> J;
    for (int a = 0; a < dim; ++a) J.col(a) = mesh.points.col(cell[a + 1]) - mesh.points.col(cell[0]);
    const double volume = std::abs(J.determinant()) / (dim == 2 ? 2.0 : 6.0) * (dim == 2 ? thickness : 1.0);
    const double m = volume / ((dim + 1) * (dim + 2));
    for (int a = 0; a <= dim; ++a)
      for (int b = 0; b <= dim; ++b)
        for (int i = 0; i < dim; ++i) t.emplace_back(dim * cell[a] + i, dim * cell[b] + i, (a == b ? 2 : 1) * m);
  }
  const auto n = static_cast<Eigen::Index>(dim * mesh.num_nodes());
  Eigen::SparseMatrix<double> M(n, n);
  M.setFromTriplets(t.begin(), t.end());
  return M;
}

/// What a ladder decided, as ContinuumAnswer::how says it.
std::string ladder_how(int refinements, long dofs, bool converged, double change, const std::string& stop) {
  std::string how = "P2 refined " + std::to_string(refinements) + "x (" + thousands(dofs) + " dofs), ";
  if (converged) return how + "converged: the last refinement moved it " + percent(change);
  if (change >= 0) return how + "not converged: the last refinement moved it " + percent(change) + " (" + stop + ")";
  return how + "convergence not checked (" + stop + ")";
}

/// What the ladder found: the finest level's answer and how it stopped.
template <class Answer> struct Ladder {
  Answer u;
  int refinements = 0;
  long dofs = 0;
  double change = -1;
  bool converged = false;
  std::string how;
};

/// P2 at refinements 0, 1, ... of `mesh`: `solve(r, dofs)` returns level r's answer (and may set
/// its dofs; they are counted otherwise), until a refinement moves it by less than the tolerance
/// (relative, whole answer), the next level's counted dofs exceed the budget, or max_refinements.
/// nullopt when not even level 0 fits the budget.
template <int dim, class Answer, class Solve>
std::optional<Ladder<Answer>> ladder(const Mesh<dim>& mesh, const ContinuumOptions& options, long budget,
                                     Solve&& solve) {
  Counts level = counts(mesh);
  if (level.p2_dofs(dim) > static_cast<double>(budget)) return std::nullopt;
  Ladder<Answer> ans;
  std::string stop;
  for (int r = 0;; ++r) {
    ans.dofs = static_cast<long>(level.p2_dofs(dim));
    Answer u = solve(r, ans.dofs);
    ans.refinements = r;
    if (r > 0) {
      const double norm = u.norm();
      ans.change = norm > 0 ? (u - ans.u).norm() / norm : 0.0;
      ans.converged = ans.change < options.tolerance;
    }
    ans.u = std::move(u);
    if (ans.converged) break;
    level = level.refined(dim);
    if (r + 1 > options.max_refinements) {
      stop = "refinement " + std::to_string(r + 1) + " is past the ladder's " + std::to_string(options.max_refinements);
      break;
    }
    if (level.p2_dofs(dim) > static_cast<double>(budget)) {
      stop = "refined once more it would need ~" + thousands(static_cast<long>(level.p2_dofs(dim))) +
             " dofs, above the budget of " + thousands(budget);
      break;
    }
  }
  ans.how = ladder_how(ans.refinements, ans.dofs, ans.converged, ans.change, stop);
  return ans;
}

/// The options of every level's static P2 solve.
FemOptions static_p2(int refinements) {
  FemOptions o;
  o.degree = 2;
  o.refinements = refinements;
  o.static_solve = true;
  o.dt = 1.0;
  return o;
}

} // namespace

template <int dim>
std::optional<ContinuumAnswers> continuum_answers(const Problem<dim>& problem, const MaterialDesc& material,
                                                  const Eigen::MatrixXd& F, const ContinuumOptions& options) {
  const Problem<dim> p = static_problem(problem);
  if (static_cast<double>(continuum_first_dofs(p.mesh)) > static_cast<double>(continuum_budget(dim, options)))
    return std::nullopt; // before the mass solve
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> mass(p1_mass(p.mesh, material.thickness));
  const Eigen::MatrixXd g = mass.solve(F);
  MaterialDesc unit = material;
  unit.density = 1.0;
  auto found = ladder<dim, Eigen::MatrixXd>(p.mesh, options, continuum_budget(dim, options), [&](int r, long&) {
    KelvinVoigtProblem<dim, SerialBackend<dim>> fem(p, unit, static_p2(r), MPI_COMM_SELF);
    return fem.body_force_answers(g);
  });
  if (!found) return std::nullopt;
  return ContinuumAnswers{std::move(found->u), found->refinements, found->change, found->converged, found->how};
}

template <int dim>
std::optional<ContinuumAnswer<dim>> continuum_static(const Problem<dim>& problem, const MaterialDesc& material,
                                                     const ContinuumOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const Problem<dim> p = static_problem(problem, options.drives_displaced);
  auto found = ladder<dim, Nodal<dim>>(p.mesh, options, continuum_budget(dim, options), [&](int r, long& dofs) {
    Trajectory<dim> out;
    const RunReport rep = simulate<dim>(p, material, static_p2(r), out, true);
    for (const auto& [key, value] : rep.extra)
      if (key == "dofs") dofs = static_cast<long>(value); // the solve's own count
    return Nodal<dim>(out.field.back());
  });
  if (!found) return std::nullopt;
  ContinuumAnswer<dim> ans;
  ans.u = std::move(found->u);
  ans.refinements = found->refinements;
  ans.dofs = found->dofs;
  ans.change = found->change;
  ans.converged = found->converged;
  ans.how = found->how;
  ans.sufficient_refinements = ans.converged ? ans.refinements - 1 : ans.refinements;
  ans.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return ans;
}

template std::optional<ContinuumAnswers> continuum_answers<2>(const Problem<2>&, const MaterialDesc&,
                                                              const Eigen::MatrixXd&, const ContinuumOptions&);
template std::optional<ContinuumAnswers> continuum_answers<3>(const Problem<3>&, const MaterialDesc&,
                                                              const Eigen::MatrixXd&, const ContinuumOptions&);
template std::optional<ContinuumAnswer<2>> continuum_static<2>(const Problem<2>&, const MaterialDesc&,
                                                               const ContinuumOptions&);
template std::optional<ContinuumAnswer<3>> continuum_static<3>(const Problem<3>&, const MaterialDesc&,
                                                               const ContinuumOptions&);

} // namespace vtb::fem
