// The Kelvin-Voigt reference's outputs: probes, reactions, strain, the samples between steps and the frames.
// Members of KelvinVoigtProblem (kelvin_voigt_problem.hh), instantiated for both backends.
#include "kelvin_voigt_problem.hh"
#include "vtb/base/atomic_file.hh"

#include "vtb/problem/cell_fields.hh"

#include <deal.II/numerics/data_out.h>

#include <Eigen/Dense>

#include <cstdio>
namespace vtb::fem {

template <int dim, class Backend>
void KelvinVoigtProblem<dim, Backend>::record(double t, Trajectory<dim>& out, bool record_field) {
  out.t.push_back(t);
  std::vector<double> field(static_cast<std::size_t>(m_model.num_nodes()) * dim, 0.0);
  for (std::size_t k = 0; k < field.size(); ++k)
    if (m_node[k] != kUnseen && m_owned.is_element(m_node[k])) field[k] = m_u[m_node[k]];
  m_backend.sum(field);
  const Eigen::Map<const Nodal<dim>> nodal(field.data(), dim, m_model.num_nodes());
  std::vector<Vec<dim>> pu;
  for (std::size_t p = 0; p < m_model.probes.size(); ++p) pu.push_back(m_model.probe_displacement(p, nodal));
  out.probe_u.push_back(pu);
  load_vector(t, m_f);
  if (m_opt.nonlinear()) {
    nonlinear_force(m_u, m_v, m_rhs, 0.0, false);
    if (!m_opt.static_solve) {
      m_tmp = m_a;
      m_tmp.add(m_mat.mass_damping, m_v);
      m_M.vmult_add(m_rhs, m_tmp);
    }
  } else {
    m_K.vmult(m_rhs, m_u);
  }
  if (!m_opt.nonlinear() && !m_opt.static_solve) {
    m_C.vmult(m_tmp, m_v);
    m_rhs += m_tmp;
    m_M.vmult(m_tmp, m_a);
    m_rhs += m_tmp;
  }
  m_rhs -= m_f;
  std::vector<double> reac(m_model.supports.size() * dim, 0.0);
  for (const auto d : m_owned)
    if (m_support_of[d] >= 0) reac[static_cast<std::size_t>(m_support_of[d]) * dim + m_comp[d]] += m_rhs[d];
  m_backend.sum(reac);
  std::vector<Vec<dim>> r(m_model.supports.size());
  for (std::size_t s = 0; s < r.size(); ++s) r[s] = Eigen::Map<const Vec<dim>>(reac.data() + s * dim);
  out.reaction.push_back(r);
  if (record_field) out.field.push_back(nodal);
  // Rotation from the field at the scene's nodes on the scene's cells (the P1 interpolant:
  // the same measure as the spring solvers; every rank holds the summed field).
  const double rotation = max_rotation(m_model.mesh, Nodal<dim>(nodal));
  if (!(rotation <= m_max_rotation)) m_max_rotation = rotation;
  m_ghosted = m_u;
  m_max_strain = std::max(m_max_strain, m_backend.max(max_principal_strain(m_mapping, m_fe, m_dofs, m_ghosted)));
  if (m_opt.frames_dir.empty()) return;
  m_frame_prev = m_frame_last; // the FE fields of the last two samples, for the frames
  m_frame_last = m_ghosted;
  if (out.t.size() == 1) write_frame(m_frame_last, 0);
}

template <int dim, class Backend>
void KelvinVoigtProblem<dim, Backend>::interpolate_samples(Trajectory<dim>& out, std::span<const double> times) {
  const double ta = out.t[out.t.size() - 2], tb = out.t.back();
  interpolate_last_step(out, times);
  if (m_opt.frames_dir.empty()) return;
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double w = step_weight(ta, tb, times[k]);
    m_frame_mix = m_frame_last;
    m_frame_mix.sadd(w, 1 - w, m_frame_prev);
    write_frame(m_frame_mix, out.t.size() - (times.size() - k));
  }
}

template <int dim, class Backend>
void KelvinVoigtProblem<dim, Backend>::write_frame(const Vector& u, std::size_t index) {
  dealii::DataOut<dim> data_out;
  data_out.attach_dof_handler(m_dofs);
  const std::vector<std::string> names(dim, "displacement");
  const std::vector<dealii::DataComponentInterpretation::DataComponentInterpretation> kinds(
      dim, dealii::DataComponentInterpretation::component_is_part_of_vector);
  data_out.add_data_vector(u, names, dealii::DataOut<dim>::type_dof_data, kinds);
  data_out.build_patches(m_mapping, static_cast<unsigned int>(m_opt.degree));
  char name[32];
  std::snprintf(name, sizeof name, "frame_%04zu.vtu", index);
  write_file_atomically(m_opt.frames_dir / name, [&](std::ostream& f) { data_out.write_vtu(f); });
}

template class KelvinVoigtProblem<2, SerialBackend<2>>;
template class KelvinVoigtProblem<3, SerialBackend<3>>;
template class KelvinVoigtProblem<2, DistributedBackend<2>>;
template class KelvinVoigtProblem<3, DistributedBackend<3>>;

} // namespace vtb::fem
