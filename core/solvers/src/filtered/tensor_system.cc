// The tensor filter's two solves with H (tensor_filter.hh): the factor, tile by tile, and one
// block V-cycle.
#include "vtb/linalg/block_multigrid.hh"
#include "vtb/linalg/block_solve.hh"
#include "vtb/linalg/ordered_ldlt.hh"
#include "vtb/solvers/tensor_filter.hh"

#include <stdexcept>

namespace vtb {

namespace {

/// f, factorised.
const OrderedLDLT& factorised(OrderedLDLT& f) {
  if (!f.factorize()) throw std::runtime_error("filtered (tensor): H is not positive definite");
  return f;
}

/// H's sparse LDL^T, ordered by nodes (block = dim) so that L is made of dim x dim tiles and
/// the step solves tile by tile; the upper triangle's values are stored.
template <int dim> class FactorSystem final : public TensorSystem<dim> {
public:
  explicit FactorSystem(const Eigen::SparseMatrix<double>& H) : m_h(H, dim), m_blocks(factorised(m_h)) {}
  Eigen::Index size() const override { return m_h.size(); }
  int index(int r) const override { return m_h.ordered(r); }
  double* values() override { return m_h.values(); }
  std::size_t value_count() const override { return static_cast<std::size_t>(m_h.nonzeros()); }
  long offset(int r, int c) const override {
    const int ro = m_h.ordered(r), co = m_h.ordered(c);
    return ro > co ? -1 : m_h.offset(ro, co);
  }
  void refresh() override {
    m_h.factorize(); // H(beta) is H(0) plus positive semidefinite terms: positive definite
    m_blocks.refresh();
  }
  void begin_refresh() override { m_h.begin_factorize(); }
  bool refresh_part(double share) override {
    // Rows of the factor up to the share of its work; the tiles copied with the last part.
    if (!m_h.factorize_part(share * m_h.factorize_work())) return false;
    if (!m_h.factorized()) throw std::runtime_error("filtered (tensor): H is not positive definite");
    m_blocks.refresh();
    return true;
  }
  std::unique_ptr<TensorSystem<dim>> twin(const Eigen::SparseMatrix<double>& H) const override {
    return std::make_unique<FactorSystem>(H);
  }
  void solve(Eigen::Ref<Eigen::VectorXd> y) override {
    m_blocks.solve_in_place(Eigen::Map<Nodal<dim>>(y.data(), dim, y.size() / dim)); // tile k = rows k dim ..
  }
  bool solve_turned(const double* force, const double* turn, const int* node, const int* slot, double scale, double* y,
                    double* out) override {
    if constexpr (dim == 2) {
      m_blocks.solve_turned(force, turn, node, slot, scale, y, out);
      return true;
    }
    return false;
  }

private:
  OrderedLDLT m_h;
  BlockSolve<dim> m_blocks;
};

/// One block V-cycle B (0 < B <= H^-1); the vector holds kLanes values per free node.
template <int dim> class MultigridSystem final : public TensorSystem<dim> {
public:
  static constexpr int W = BlockMultigrid<dim>::kLanes;
  MultigridSystem(const Eigen::SparseMatrix<double>& H, const Nodal<dim>& x)
      : m_mg(H, x), m_b(static_cast<std::size_t>(x.cols()) * W, 0.0) {}
  Eigen::Index size() const override { return static_cast<Eigen::Index>(m_b.size()); }
  int index(int r) const override { return (r / dim) * W + r % dim; }
  double* values() override { return m_mg.values(); }
  std::size_t value_count() const override { return m_mg.value_count(); }
  long offset(int r, int c) const override { return m_mg.offset(r, c); }
  void refresh() override { m_mg.refresh(); }
  void begin_refresh() override { m_mg.begin_refresh(); }
  bool refresh_part(double share) override { return m_mg.refresh_part(share); }
  std::unique_ptr<TensorSystem<dim>> twin(const Eigen::SparseMatrix<double>& /*H: this one's*/) const override {
    return std::make_unique<MultigridSystem>(*this);
  }
  void solve(Eigen::Ref<Eigen::VectorXd> y) override {
    std::copy(y.data(), y.data() + y.size(), m_b.begin()); // the pads are 0 in and out
    m_mg.apply(m_b.data(), y.data());
  }

private:
  BlockMultigrid<dim> m_mg;
  std::vector<double> m_b;
};

} // namespace

template <int dim>
std::unique_ptr<TensorSystem<dim>> make_warped_system(const Eigen::SparseMatrix<double>& H, const Nodal<dim>& x,
                                                      bool multigrid) {
  if (multigrid) return std::make_unique<MultigridSystem<dim>>(H, x);
  return std::make_unique<FactorSystem<dim>>(H);
}

template std::unique_ptr<TensorSystem<2>> make_warped_system<2>(const Eigen::SparseMatrix<double>&, const Nodal<2>&,
                                                                bool);
template std::unique_ptr<TensorSystem<3>> make_warped_system<3>(const Eigen::SparseMatrix<double>&, const Nodal<3>&,
                                                                bool);

} // namespace vtb
