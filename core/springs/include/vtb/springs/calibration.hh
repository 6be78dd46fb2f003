#pragma once
/// \file
/// Lumped masses and spring stiffness calibration from Young's modulus (and Poisson's ratio).

#include "vtb/meshes/mesh.hh"
#include "vtb/problem/scene.hh"
#include "vtb/springs/spring_kernels.hh"

#include <Eigen/SparseCore>

#include <string_view>

namespace vtb {

/// Lumped nodal masses: density x area x thickness / 3 per triangle vertex (2D, plane
/// stress), density x volume / 4 per tetrahedron vertex (3D).
template <int dim> Eigen::VectorXd lumped_masses(const Mesh<dim>& mesh, double density, double thickness);

/// Van Gelder (1998): k_c = E t sum_{e ∋ c} A_e / |c|^2 in 2D (t = thickness) and, by the
/// same construction, k_c = E sum_{e ∋ c} V_e / |c|^2 in 3D. Does not use nu; exact for the
/// equilateral lattice with nu = 1/3 in 2D. Returned per edge of unique_edges(mesh).
template <int dim> Eigen::VectorXd van_gelder_stiffness(const Mesh<dim>& mesh, double young_modulus, double thickness);

/// Lloyd, Szekely and Harders (2007): per element, the spring constants that make the
/// element's spring stiffness matrix closest (Frobenius norm) to the linear FEM stiffness
/// matrix of that element with E and nu (plane stress with thickness in 2D); a constant
/// that would be negative is held at zero and the rest refitted. Summed over the elements
/// sharing an edge. For an equilateral triangle with nu = 1/3 it is the exact k = sqrt(3)/4 E t.
template <int dim>
Eigen::VectorXd lloyd_stiffness(const Mesh<dim>& mesh, double young_modulus, double poisson_ratio, double thickness);

/// Lloyd's element fit with one more constant per element, the rest stiffness k_c g g^T of a
/// volume term (cell_volumes.hh): the springs' constants per edge (returned) and k_c per cell
/// (cell_stiffness), both held non-negative. The springs carry the element's Cauchy part and
/// k_c what the Cauchy relation leaves of lambda: on an equilateral triangle none at nu = 1/3
/// (plane stress), growing with nu above; a tetrahedron's six edges are not an isotropic
/// lattice, so some k_c remains at nu = 1/4 in 3D.
template <int dim>
Eigen::VectorXd lloyd_volume_stiffness(const Mesh<dim>& mesh, double young_modulus, double poisson_ratio,
                                       double thickness, Eigen::VectorXd& cell_stiffness);

/// The Poisson ratio that a network of central springs implies on a regular lattice
/// (Cauchy relation): 1/3 for triangles, 1/4 for tetrahedra. Reported in summary.json; the
/// scene's nu enters only through the Lloyd fit.
constexpr double spring_poisson_ratio(int dim) {
  return dim == 2 ? 1.0 / 3.0 : 0.25;
}

/// Linear FEM element stiffness matrix of a simplex, (dim+1)*dim square, nodes-major
/// ordering (node a, component i) -> a*dim + i. Plane stress with thickness in 2D.
template <int dim>
Eigen::MatrixXd fem_element_stiffness(const Mesh<dim>& mesh, const typename Mesh<dim>::Cell& cell, double young_modulus,
                                      double poisson_ratio, double thickness);

/// The global linear FEM (P1) stiffness matrix of the mesh, dim n square, node-major dofs
/// (node v, component i) -> dim v + i, both triangles stored; rigid motions in its null space.
template <int dim>
Eigen::SparseMatrix<double> fem_stiffness_matrix(const Mesh<dim>& mesh, double young_modulus, double poisson_ratio,
                                                 double thickness);

} // namespace vtb
