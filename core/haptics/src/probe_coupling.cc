#include "vtb/haptics/probe_coupling.hh"

#include "vtb/haptics/coupling.hh"

namespace vtb {

template <int dim>
typename ProbeCoupling<dim>::Vec ProbeCoupling<dim>::cycle(Contacts<dim>& contacts, std::size_t probe,
                                                           const Vec& handle, const Vec& handle_velocity,
                                                           const Body& body) {
  if (body.fresh) m_history = ForceHistory<dim>{}; // a new physics step's force comes from here on
  const bool whole = m_blend_cycles <= 1;
  // Multirate: the body where the local model puts it, with the last cycle's force f_prev (its
  // free motion at the last footprint, and its answer to f_prev): the contact is found on the
  // published body for the handle moved by the opposite shift, so that contact begins, holds
  // and ends on the modelled surface alike.
  const bool modelled = !whole && body.model != nullptr && body.model->valid;
  LocalModel<dim> model = modelled ? *body.model : LocalModel<dim>{};
  const Vec f_prev = m_last_touching ? m_last_solved : Vec::Zero();
  Vec shift = Vec::Zero();
  if (!whole) {
    if (m_last_touching) shift += body.age * footprint_mean<dim>(m_last_footprint, body.v);
    if (modelled) shift += model.compliance * (f_prev - model.applied);
  }
  ContactResult<dim> c;
  if (body.finite) c = contacts.update(probe, Vec(handle - shift), body.x);
  if (c.touching) c.proxy += shift;
  model.applied = f_prev; // the proxy now answers f_prev: the model goes on from there
  m_proxy = c.proxy;
  Vec raw = Vec::Zero();
  if (c.touching) {
    raw = virtual_coupling<dim>(c, handle, handle_velocity, body.v, m_k, m_b);
    if (modelled) {
      raw = solve_against_local_model<dim>(raw, c.proxy - handle, tip_stiffness(m_k, c.footprint), model);
      m_proxy += model.compliance * (-raw - model.applied);
    }
  }
  m_last_solved = -raw;
  // What the local model predicted against what the new physics step gives: the change of the
  // coupling force at a publish, in contact on both sides of it. A physics slower than the
  // servo has that change blended in over its period (the force leaves the old model's
  // prediction for the new one linearly), so that no publish is felt as a step; a contact that
  // a publish begins (the body moved onto the handle) ramps in over it too.
  m_publish_change = body.fresh && c.touching && m_last_touching ? (raw - m_last_raw).norm() : -1.0;
  if (body.fresh && c.touching && !whole) {
    m_offset = (m_last_touching ? m_last_raw : Vec::Zero()) - raw;
    m_offset_left = m_blend_cycles;
  }
  if (!c.touching) m_offset_left = 0;
  if (m_offset_left > 0) {
    raw += m_offset * (static_cast<double>(--m_offset_left) / m_blend_cycles);
    if (const double d2 = (c.proxy - handle).squaredNorm(); d2 > 0) { // it never pulls
      const double normal = raw.dot(c.proxy - handle) / d2;
      if (normal < 0) raw -= normal * (c.proxy - handle);
    }
  }
  m_last_raw = raw;
  m_last_touching = c.touching;
  m_last_footprint = c.footprint;
  m_contact = c;
  if (!c.touching) m_proxy = handle;
  return raw;
}

template <int dim> void ProbeCoupling<dim>::rendered(const Vec& f) {
  m_history.sum -= f;
  m_history.proxy_sum += m_proxy;
  ++m_history.cycles;
  if (m_contact.touching) m_history.touched = m_contact.footprint;
}

template class ProbeCoupling<2>;
template class ProbeCoupling<3>;

} // namespace vtb
