#pragma once
/// \file
/// One probe's virtual coupling at the servo's rate, against a physics that publishes the body
/// every `blend_cycles` servo periods (multirate rendering, local_model.hh). What `vtb haptics`'
/// servo and the viewer's device mode both run each servo cycle, so that the two render a
/// contact alike:
///  - the contact is found on the published body moved by the local model (its free motion at
///    the tip back to the cycle's time, and its answer to the last cycle's force), and the
///    coupling is solved against that model;
///  - a publish's change of the force is blended in over the physics' period, and a contact
///    that a publish begins ramps in likewise: no publish is felt as a step;
///  - the forces the device renders are summed for the next physics step (applied_force).
/// A physics stepping every servo period (blend_cycles <= 1) is the plain coupling against the
/// body it published. No allocation.

#include "vtb/haptics/contact_result.hh"
#include "vtb/haptics/contacts.hh"
#include "vtb/haptics/local_model.hh"
#include "vtb/linalg/nodal.hh"

namespace vtb {

template <int dim> class ProbeCoupling {
public:
  using Vec = Eigen::Matrix<double, dim, 1>;

  /// What one cycle sees of the published body.
  struct Body {
    const Nodal<dim>& x; ///< where the contact is searched (the published nodes)
    const Nodal<dim>& v; ///< their velocities
    double age;          ///< the cycle's time less the publish's, clamped by the caller (<= 0 when published ahead)
    bool fresh;          ///< the first cycle that sees this publish
    bool finite;         ///< the publish can be trusted
    const LocalModel<dim>* model; ///< the probe's local model over the published step; null: none
  };

  /// k, b: the virtual coupling's stiffness (N/m) and damping (N s/m).
  ProbeCoupling(double k, double b, int blend_cycles) : m_k(k), m_b(b), m_blend_cycles(blend_cycles) {}

  /// The physics' period in servo cycles (a viewer may change its step).
  void set_blend_cycles(int n) { m_blend_cycles = n; }

  /// One servo cycle with the handle at `handle` moving at `handle_velocity` (world): the
  /// coupling's force on the handle, before shaping. `probe`: this probe's index in `contacts`.
  Vec cycle(Contacts<dim>& contacts, std::size_t probe, const Vec& handle, const Vec& handle_velocity,
            const Body& body);

  /// The shaped force the device rendered this cycle: its reaction joins the step's history.
  void rendered(const Vec& f);

  const ContactResult<dim>& contact() const { return m_contact; }
  /// The forces on the body since the last publish (applied_force turns them into the step's).
  const ForceHistory<dim>& history() const { return m_history; }
  /// The coupling force's change at this cycle's publish, in contact on both sides of it (the
  /// local model's prediction error, N); negative when this cycle saw none.
  double publish_change() const { return m_publish_change; }

private:
  double m_k, m_b;
  int m_blend_cycles;
  ContactResult<dim> m_contact;
  ForceHistory<dim> m_history;
  Vec m_last_raw = Vec::Zero();    ///< the last cycle's coupling force
  Vec m_last_solved = Vec::Zero(); ///< the last cycle's force on the body, as solved (before blending)
  bool m_last_touching = false;
  Footprint m_last_footprint;
  Vec m_proxy = Vec::Zero();  ///< where the local model put the proxy, with the force solved against it
  Vec m_offset = Vec::Zero(); ///< the change at the last publish, blended out
  int m_offset_left = 0;      ///< the cycles of it left
  double m_publish_change = -1;
};

} // namespace vtb
