// `vtb haptics`'s output files (session.hh): haptics.csv and summary.json, all or nothing.
#include "vtb/base/atomic_file.hh"
#include "vtb/haptics/session.hh"

#include <nlohmann/json.hpp>

#include <iomanip>
#include <sstream>

namespace vtb {

void write_haptics(const HapticsReport& r, const std::filesystem::path& dir, const std::string& scene_name) {
  std::ostringstream csv;
  csv << std::setprecision(10) << "t,hx,hy,fx,fy";
  for (std::size_t i = 1; i < r.probes.size(); ++i)
    for (const char* c : {"hx_", "hy_", "fx_", "fy_"}) csv << ',' << c << i;
  csv << '\n';
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    csv << r.t[k];
    for (const ProbeTrace& p : r.probes) csv << ',' << p.hx[k] << ',' << p.hy[k] << ',' << p.fx[k] << ',' << p.fy[k];
    csv << '\n';
  }
  nlohmann::ordered_json j;
  j["scene"] = scene_name;
  j["device"] = r.device;
  j["device_packets"] = r.link.received;
  j["device_packets_stale"] = r.link.stale;
  j["device_packets_lost"] = r.link.lost;
  j["device_packets_malformed"] = r.link.malformed;
  j["device_faults"] = r.link.faults;
  j["device_silent_cycles"] = r.link.silent_cycles;
  j["device_silent_time"] = r.link.first_silent_time;
  j["device_rtt_us_p50"] = r.link.rtt_p50_us;
  j["device_rtt_us_p99"] = r.link.rtt_p99_us;
  j["samples"] = r.samples;
  j["rate_hz_mean"] = r.rate_hz_mean;
  j["period_p99_us"] = r.period_p99_us;
  j["period_max_us"] = r.period_max_us;
  j["deadline_misses"] = r.deadline_misses;
  j["realtime_setup"] = r.realtime_setup;
  j["max_force"] = r.max_force;
  j["saturated_samples"] = r.saturated_samples;
  j["nonfinite_samples"] = r.nonfinite_samples;
  j["energy_to_user"] = r.energy_to_user;
  j["fault_time"] = r.fault_time;
  j["force_zero_time"] = r.force_zero_time;
  if (!r.fault_reason.empty()) j["fault_reason"] = r.fault_reason;
  j["physics_steps"] = r.physics_steps;
  j["physics_step_median_us"] = r.physics_step_median_us;
  j["physics_step_max_us"] = r.physics_step_max_us;
  j["physics_step_budget_us"] = r.physics_step_budget_us;
  j["physics_steps_over_budget"] = r.physics_steps_over_budget;
  j["physics_dt_us"] = r.physics_dt_us;
  j["physics_time_ratio"] = r.physics_time_ratio;
  j["local_model"] = r.local_model;
  j["local_model_error_rms"] = r.local_model_error_rms;
  j["local_model_error_max"] = r.local_model_error_max;
  j["contact_tree_builds_physics"] = r.contact_tree_builds_physics;
  j["contact_tree_builds_servo"] = r.contact_tree_builds_servo;
  if (!r.physics_filter.empty()) j["physics_filter"] = r.physics_filter;
  if (!r.springs.empty()) j["springs"] = r.springs;
  if (!r.physics_filter_reason.empty()) j["physics_filter_reason"] = r.physics_filter_reason;
  j["tick_median_us"] = r.tick_median_us;
  j["tick_p99_us"] = r.tick_p99_us;
  j["dim"] = r.dim;
  j["coupling_stiffness"] = r.coupling_stiffness;
  j["tip_radius"] = r.tip_radius;
  j["surface_mean_edge"] = r.surface_mean_edge;
  j["notes"] = r.notes;
  j["probes"] = nlohmann::ordered_json::array();
  for (const ProbeTrace& p : r.probes)
    j["probes"].push_back({{"max_force", p.max_force},
                           {"saturated_samples", p.saturated_samples},
                           {"nonfinite_samples", p.nonfinite_samples},
                           {"energy_to_user", p.energy_to_user},
                           {"contact_samples", p.contact_samples},
                           {"unresolved_samples", p.unresolved_samples},
                           {"truncated_samples", p.truncated_samples},
                           {"footprint_nodes_max", p.footprint_nodes_max}});
  write_files_atomically(dir, {{"haptics.csv", csv.str()}, {"summary.json", j.dump(2) + "\n"}});
}

} // namespace vtb
