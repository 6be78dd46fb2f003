#include "vtb/problem/output.hh"
#include "vtb/problem/solver_names.hh"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace vtb {

std::string summary_json(const RunReport& r, const std::string& scene_name) {
  nlohmann::ordered_json j;
  j["scene"] = scene_name;
  j["solver"] = r.solver;
  j["dim"] = r.dim;
  j["nodes"] = r.nodes;
  if (r.solver != solvers::kFem) {
    j["free_nodes"] = r.free_nodes;
    j["springs"] = r.springs;
  }
  // dt is a fixed-step solver's step; CVODE chooses its own, so it reports their mean instead.
  if (r.solver == solvers::kCvode)
    j["mean_step"] = r.dt;
  else
    j["dt"] = r.dt;
  j["duration"] = r.duration;
  j["steps"] = r.steps_taken;
  j["steps_planned"] = r.steps;
  j["precompute_seconds"] = r.precompute_seconds;
  j["step_seconds"] = {{"mean", r.step_seconds.mean}, {"median", r.step_seconds.median}, {"p99", r.step_seconds.p99}};
  j["total_seconds"] = r.total_seconds;
  if (r.step_budget > 0) {
    j["step_budget"] = r.step_budget;
    j["steps_over_budget"] = r.steps_over_budget;
    j["over_budget_share"] =
        r.steps_taken > 0 ? static_cast<double>(r.steps_over_budget) / static_cast<double>(r.steps_taken) : 0.0;
  }
  j["stable"] = r.stable;
  if (!r.stable) {
    j["failure"] = r.failure;
    j["failure_time"] = r.failure_time;
  }
  j["max_strain"] = r.max_strain;
  j["max_rotation"] = r.max_rotation;
  if (r.solver != solvers::kFem) j["max_spring_strain"] = r.max_spring_strain;
  if (r.solver != solvers::kFem) {
    j["courant_dt_estimate"] = r.courant_dt;
    j["calibration"] = r.calibration;
    j["calibration_requested"] = r.calibration_requested;
    j["calibration_seconds"] = r.calibration_seconds;
    if (std::isfinite(r.calibration_validation)) { // a fit ran (or was read from the cache)
      j["calibration_cached"] = r.calibration_cached;
      j["calibration_validation_error"] = r.calibration_validation;
    }
    if (std::isfinite(r.calibration_load_error)) {
      j["calibration_load_error"] = r.calibration_load_error;
      j["calibration_load_trained"] = r.calibration_own_loads; // the fit saw these loads
      j["calibration_yardstick"] = r.calibration_yardstick;
    }
    if (std::isfinite(r.mesh_fem_load_error)) j["mesh_fem_load_error"] = r.mesh_fem_load_error;
    if (!r.calibration_target.empty()) j["calibration_target"] = r.calibration_target;
    if (!r.calibration_note.empty()) j["calibration_note"] = r.calibration_note;
    j["effective_poisson_ratio"] = r.effective_poisson_ratio;
  }
  // Counts (cells, dofs, steps, iterations, degree...) print as integers, not 600.0; times,
  // tolerances and ratios as numbers.
  for (const auto& [key, value] : r.extra) {
    const bool time = key.size() > 8 && key.compare(key.size() - 8, 8, "_seconds") == 0;
    if (!time && std::isfinite(value) && value == std::floor(value) && std::abs(value) < 9.0e15)
      j[key] = static_cast<long long>(value);
    else
      j[key] = value;
  }
  if (r.solver == solvers::kFiltered) {
    j["filter"] = r.filter;
    if (!r.filter_requested.empty()) j["filter_requested"] = r.filter_requested;
    if (!r.filter_reason.empty()) j["filter_reason"] = r.filter_reason;
    if (!r.filter_most_steps.empty()) j["filter_most_steps"] = r.filter_most_steps;
    if (r.steps_taken > 0)
      j["fallback_share"] = static_cast<double>(r.fallback_steps) / static_cast<double>(r.steps_taken);
    j["momentum_correction"] = r.momentum_correction;
    j["strain_limit"] = r.strain_limit;
  }
  return j.dump(2) + "\n";
}

void write_pvd(const std::filesystem::path& dir, const std::vector<double>& times) {
  std::ostringstream os;
  os << std::setprecision(12)
     << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  for (std::size_t k = 0; k < times.size(); ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "frames/frame_%04zu.vtu", k);
    os << "<DataSet timestep=\"" << times[k] << "\" group=\"\" part=\"0\" file=\"" << name << "\"/>\n";
  }
  os << "</Collection>\n</VTKFile>\n";
  write_files_atomically(dir, {{"frames.pvd", os.str()}});
}

/// The summary with each probe's node and its distance from the probe's scene point.
template <int dim> std::string with_probes(const std::string& summary, const Problem<dim>& model) {
  auto j = nlohmann::ordered_json::parse(summary);
  j["probes"] = nlohmann::ordered_json::array();
  for (std::size_t p = 0; p < model.probes.size(); ++p)
    j["probes"].push_back({{"name", model.probes[p].first},
                           {"node", model.probes[p].second},
                           {"distance", p < model.probe_distance.size() ? model.probe_distance[p] : 0.0}});
  return j.dump(2) + "\n";
}

template <int dim>
void write_run_outputs(const std::filesystem::path& dir, const Problem<dim>& model, const Trajectory<dim>& traj,
                       const RunReport& report, const std::string& scene_name) {
  std::ostringstream probes, reactions;
  probes << std::setprecision(10) << "t,probe,ux,uy,uz\n";
  reactions << std::setprecision(10) << "t,region,fx,fy,fz\n";
  for (std::size_t k = 0; k < traj.t.size(); ++k) {
    for (std::size_t p = 0; p < model.probes.size(); ++p) {
      const auto& u = traj.probe_u[k][p];
      probes << traj.t[k] << ',' << model.probes[p].first << ',' << u[0] << ',' << u[1] << ','
             << (dim == 3 ? u[dim - 1] : 0.0) << '\n';
    }
    for (std::size_t q = 0; q < model.supports.size(); ++q) {
      const auto& f = traj.reaction[k][q];
      reactions << traj.t[k] << ',' << model.supports[q].name << ',' << f[0] << ',' << f[1] << ','
                << (dim == 3 ? f[dim - 1] : 0.0) << '\n';
    }
  }
  write_files_atomically(dir, {{"probes.csv", probes.str()},
                               {"reactions.csv", reactions.str()},
                               {"summary.json", with_probes(summary_json(report, scene_name), model)}});
}

template <int dim>
RunTables run_tables(const Problem<dim>& model, const Trajectory<dim>& traj, const RunReport& report,
                     const std::string& scene_name) {
  RunTables out;
  out.dim = dim;
  out.report = report;
  const auto padded = [](const Vec<dim>& x) { return std::array<double, 3>{x[0], x[1], dim == 3 ? x[dim - 1] : 0.0}; };
  for (std::size_t k = 0; k < traj.t.size(); ++k) {
    for (std::size_t p = 0; p < model.probes.size(); ++p) {
      out.probe_t.push_back(traj.t[k]);
      out.probe_name.push_back(model.probes[p].first);
      out.probe_u.push_back(padded(traj.probe_u[k][p]));
    }
    for (std::size_t q = 0; q < model.supports.size(); ++q) {
      out.reaction_t.push_back(traj.t[k]);
      out.region.push_back(model.supports[q].name);
      out.reaction_f.push_back(padded(traj.reaction[k][q]));
    }
  }
  out.summary_json = with_probes(summary_json(report, scene_name), model);
  return out;
}

template <int dim>
void finish_run(const std::filesystem::path& dir, const Problem<dim>& model, const Trajectory<dim>& traj,
                const RunReport& report, const std::string& scene_name, RunTables* tables) {
  if (!dir.empty()) write_run_outputs(dir, model, traj, report, scene_name);
  if (tables) *tables = run_tables(model, traj, report, scene_name);
}

template void finish_run<2>(const std::filesystem::path&, const Problem<2>&, const Trajectory<2>&, const RunReport&,
                            const std::string&, RunTables*);
template void finish_run<3>(const std::filesystem::path&, const Problem<3>&, const Trajectory<3>&, const RunReport&,
                            const std::string&, RunTables*);
template RunTables run_tables<2>(const Problem<2>&, const Trajectory<2>&, const RunReport&, const std::string&);
template RunTables run_tables<3>(const Problem<3>&, const Trajectory<3>&, const RunReport&, const std::string&);

template void write_run_outputs<2>(const std::filesystem::path&, const Problem<2>&, const Trajectory<2>&,
                                   const RunReport&, const std::string&);
template void write_run_outputs<3>(const std::filesystem::path&, const Problem<3>&, const Trajectory<3>&,
                                   const RunReport&, const std::string&);

} // namespace vtb
