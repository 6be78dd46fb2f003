#include "vtb/springs/calibration.hh"

#include "vtb/springs/cell_volumes.hh"

#include <Eigen/Dense>
#include <algorithm>

namespace vtb {

template <int dim> Eigen::VectorXd lumped_masses(const Mesh<dim>& mesh, double density, double thickness) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(mesh.num_nodes());
  const double scale = density * (dim == 2 ? thickness : 1.0) / (dim + 1);
  for (const auto& c : mesh.cells) {
    const double share = scale * std::abs(signed_measure(mesh, c));
    for (int v : c) m[v] += share;
  }
  return m;
}

namespace {

/// Index of edge (a, b) in the sorted unique edge list.
int edge_index(const std::vector<std::array<int, 2>>& edges, int a, int b) {
  const std::array<int, 2> key{std::min(a, b), std::max(a, b)};
  return static_cast<int>(std::lower_bound(edges.begin(), edges.end(), key) - edges.begin());
}

template <int dim> Eigen::Matrix<double, dim*(dim + 1) / 2, dim*(dim + 1) / 2> elasticity(double E, double nu) {
  constexpr int nv = dim * (dim + 1) / 2;
  Eigen::Matrix<double, nv, nv> D = Eigen::Matrix<double, nv, nv>::Zero();
  if constexpr (dim == 2) { // plane stress, engineering shear strain
    const double f = E / (1 - nu * nu);
    D << f, f * nu, 0, f * nu, f, 0, 0, 0, f * (1 - nu) / 2;
  } else {
    const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
    const double mu = E / (2 * (1 + nu));
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) D(i, j) = lambda;
      D(i, i) = lambda + 2 * mu;
      D(3 + i, 3 + i) = mu;
    }
  }
  return D;
}

} // namespace

template <int dim>
Eigen::MatrixXd fem_element_stiffness(const Mesh<dim>& mesh, const typename Mesh<dim>::Cell& cell, double E, double nu,
                                      double thickness) {
  constexpr int nv = dim * (dim + 1) / 2;
  Mat<dim> J;
  for (int k = 0; k < dim; ++k) J.col(k) = mesh.points.col(cell[k + 1]) - mesh.points.col(cell[0]);
  const Mat<dim> Jinv = J.inverse();
  Eigen::Matrix<double, dim, dim + 1> grad; // column a = grad of barycentric a
  for (int a = 1; a <= dim; ++a) grad.col(a) = Jinv.row(a - 1).transpose();
  grad.col(0) = -grad.rightCols(dim).rowwise().sum();
  Eigen::Matrix<double, nv, dim*(dim + 1)> B = Eigen::Matrix<double, nv, dim*(dim + 1)>::Zero();
  for (int a = 0; a <= dim; ++a) {
    const int c = a * dim;
    if constexpr (dim == 2) {
      B(0, c) = grad(0, a);
      B(1, c + 1) = grad(1, a);
      B(2, c) = grad(1, a);
      B(2, c + 1) = grad(0, a);
    } else {
      for (int i = 0; i < 3; ++i) B(i, c + i) = grad(i, a);
      B(3, c + 1) = grad(2, a); // yz
      B(3, c + 2) = grad(1, a);
      B(4, c) = grad(2, a); // xz
      B(4, c + 2) = grad(0, a);
      B(5, c) = grad(1, a); // xy
      B(5, c + 1) = grad(0, a);
    }
  }
  const double V = std::abs(J.determinant()) / (dim == 2 ? 2.0 : 6.0) * (dim == 2 ? thickness : 1.0);
  return V * B.transpose() * elasticity<dim>(E, nu) * B;
}

template <int dim>
Eigen::SparseMatrix<double> fem_stiffness_matrix(const Mesh<dim>& mesh, double E, double nu, double thickness) {
  // Assembled into its sparsity pattern (each node's column holds its own and its neighbours'
  // rows) rather than through triplets: on a 10k-node tetrahedral mesh the 144 triplets per
  // cell and setFromTriplets' copy of them took about 200 MB at once, the peak of a run
  // (docs/performance.md). The entries are summed cell by cell in the same order as before.
  const int n = mesh.num_nodes();
  std::vector<std::vector<int>> near(static_cast<std::size_t>(n));
  for (const auto& c : mesh.cells)
    for (int a = 0; a <= dim; ++a)
      for (int b = 0; b <= dim; ++b) near[static_cast<std::size_t>(c[a])].push_back(c[b]);
  Eigen::VectorXi per_column(dim * n);
  for (int v = 0; v < n; ++v) {
    auto& nb = near[static_cast<std::size_t>(v)];
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    per_column.segment<dim>(dim * v).setConstant(dim * static_cast<int>(nb.size()));
  }
  Eigen::SparseMatrix<double> K(dim * n, dim * n);
  K.reserve(per_column);
  for (int v = 0; v < n; ++v) // rows in increasing order within each column: appended in place
    for (int j = 0; j < dim; ++j)
      for (int w : near[static_cast<std::size_t>(v)])
        for (int i = 0; i < dim; ++i) K.insert(dim * w + i, dim * v + j) = 0.0;
  K.makeCompressed();
  const int* outer = K.outerIndexPtr();
  const int* inner = K.innerIndexPtr();
  double* value = K.valuePtr();
  for (const auto& c : mesh.cells) {
    const Eigen::MatrixXd Ke = fem_element_stiffness(mesh, c, E, nu, thickness);
    for (int b = 0; b <= dim; ++b)
      for (int j = 0; j < dim; ++j) {
        const int col = dim * c[static_cast<std::size_t>(b)] + j;
        for (int a = 0; a <= dim; ++a) {
          // Node a's rows start at its place in this column (rows of one node are consecutive).
          const int row0 = dim * c[static_cast<std::size_t>(a)];
          const int* at = std::lower_bound(inner + outer[col], inner + outer[col + 1], row0);
          const auto k = static_cast<std::size_t>(at - inner);
          for (int i = 0; i < dim; ++i) value[k + static_cast<std::size_t>(i)] += Ke(a * dim + i, b * dim + j);
        }
      }
  }
  return K;
}

template <int dim> Eigen::VectorXd van_gelder_stiffness(const Mesh<dim>& mesh, double E, double thickness) {
  const auto edges = unique_edges(mesh);
  Eigen::VectorXd k = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(edges.size()));
  const double t = dim == 2 ? thickness : 1.0;
  for (const auto& c : mesh.cells) {
    const double measure = std::abs(signed_measure(mesh, c));
    for (int a = 0; a <= dim; ++a)
      for (int b = a + 1; b <= dim; ++b) {
        const double l2 = (mesh.points.col(c[a]) - mesh.points.col(c[b])).squaredNorm();
        k[edge_index(edges, c[a], c[b])] += E * t * measure / l2;
      }
  }
  return k;
}

namespace {

/// Lloyd's element fit, with (kVolume) or without a volume term's rest stiffness k_c g g^T as
/// one more constant of each element: the springs' constants summed per edge into k, the
/// volume's per cell into cell_k (when kVolume).
template <int dim, bool kVolume>
void lloyd_fit(const Mesh<dim>& mesh, double E, double nu, double thickness, Eigen::VectorXd& k,
               Eigen::VectorXd* cell_k) {
  constexpr int ns = dim * (dim + 1) / 2; // edges per simplex
  constexpr int ne = ns + (kVolume ? 1 : 0);
  constexpr int n = dim * (dim + 1); // element dofs
  const auto edges = unique_edges(mesh);
  k = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(edges.size()));
  if (cell_k) *cell_k = Eigen::VectorXd::Zero(mesh.num_cells());
  std::array<Eigen::Matrix<double, n, n>, ne> S;
  std::array<std::array<int, 2>, ns> local{};
  for (std::size_t ci = 0; ci < mesh.cells.size(); ++ci) {
    const auto& c = mesh.cells[ci];
    const Eigen::MatrixXd K = fem_element_stiffness(mesh, c, E, nu, thickness);
    int e = 0;
    for (int a = 0; a <= dim; ++a)
      for (int b = a + 1; b <= dim; ++b, ++e) {
        const Vec<dim> d = mesh.points.col(c[b]) - mesh.points.col(c[a]);
        const Mat<dim> nn = d * d.transpose() / d.squaredNorm();
        S[e].setZero();
        S[e].template block<dim, dim>(a * dim, a * dim) = nn;
        S[e].template block<dim, dim>(b * dim, b * dim) = nn;
        S[e].template block<dim, dim>(a * dim, b * dim) = -nn;
        S[e].template block<dim, dim>(b * dim, a * dim) = -nn;
        local[e] = {c[a], c[b]};
      }
    if constexpr (kVolume) { // the volume ratio's rest gradients, stacked by node (cell_volumes.hh)
      const auto X = [&](int i) -> Vec<dim> { return mesh.points.col(i); };
      const Eigen::Matrix<double, dim, dim + 1> b = rest_gradients<dim>(edge_matrix<dim>(c, X).inverse());
      const Eigen::Map<const Eigen::Matrix<double, n, 1>> g(b.data());
      S[ns] = g * g.transpose();
    }
    Eigen::Matrix<double, ne, ne> G;
    Eigen::Matrix<double, ne, 1> rhs;
    for (int p = 0; p < ne; ++p) {
      rhs[p] = (S[p].array() * K.array()).sum();
      for (int q = 0; q < ne; ++q) G(p, q) = (S[p].array() * S[q].array()).sum();
    }
    // Least squares with non-negative constants: drop negative ones and refit.
    std::array<bool, ne> active;
    active.fill(true);
    Eigen::Matrix<double, ne, 1> x = Eigen::Matrix<double, ne, 1>::Zero();
    for (int iter = 0; iter < ne; ++iter) {
      Eigen::Matrix<double, ne, ne> Ga = G;
      Eigen::Matrix<double, ne, 1> ra = rhs;
      for (int p = 0; p < ne; ++p)
        if (!active[static_cast<std::size_t>(p)]) {
          Ga.row(p).setZero();
          Ga.col(p).setZero();
          Ga(p, p) = 1;
          ra[p] = 0;
        }
      x = Ga.ldlt().solve(ra);
      bool changed = false;
      for (int p = 0; p < ne; ++p)
        if (active[static_cast<std::size_t>(p)] && x[p] < 0) {
          active[static_cast<std::size_t>(p)] = false;
          changed = true;
        }
      if (!changed) break;
    }
    for (int p = 0; p < ns; ++p)
      k[edge_index(edges, local[static_cast<std::size_t>(p)][0], local[static_cast<std::size_t>(p)][1])] +=
          std::max(0.0, x[p]);
    if constexpr (kVolume) (*cell_k)[static_cast<Eigen::Index>(ci)] = std::max(0.0, x[ns]);
  }
}

} // namespace

template <int dim> Eigen::VectorXd lloyd_stiffness(const Mesh<dim>& mesh, double E, double nu, double thickness) {
  Eigen::VectorXd k;
  lloyd_fit<dim, false>(mesh, E, nu, thickness, k, nullptr);
  return k;
}

template <int dim>
Eigen::VectorXd lloyd_volume_stiffness(const Mesh<dim>& mesh, double E, double nu, double thickness,
                                       Eigen::VectorXd& cell_stiffness) {
  Eigen::VectorXd k;
  lloyd_fit<dim, true>(mesh, E, nu, thickness, k, &cell_stiffness);
  return k;
}

#define VTB_INSTANTIATE(D)                                                                                             \
  template Eigen::VectorXd lumped_masses<D>(const Mesh<D>&, double, double);                                           \
  template Eigen::VectorXd van_gelder_stiffness<D>(const Mesh<D>&, double, double);                                    \
  template Eigen::VectorXd lloyd_stiffness<D>(const Mesh<D>&, double, double, double);                                 \
  template Eigen::VectorXd lloyd_volume_stiffness<D>(const Mesh<D>&, double, double, double, Eigen::VectorXd&);        \
  template Eigen::MatrixXd fem_element_stiffness<D>(const Mesh<D>&, const Mesh<D>::Cell&, double, double, double);     \
  template Eigen::SparseMatrix<double> fem_stiffness_matrix<D>(const Mesh<D>&, double, double, double);
VTB_INSTANTIATE(2)
VTB_INSTANTIATE(3)
#undef VTB_INSTANTIATE

} // namespace vtb
