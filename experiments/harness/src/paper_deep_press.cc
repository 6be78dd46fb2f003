// The deep press's series and numbers for the paper (deep_press.csv, reproduce_deep_press.cc):
// force against depth per material and model, and the springs' gap to the neo-Hookean continuum.
#include "paper_data_parts.hh"

#include <cmath>
#include <string>

namespace vtb::harness::paper {
namespace {

/// The force at which a model's curve (through the origin, in file order) reaches `depth`
/// (a share of the layer), by linear interpolation; NaN beyond its deepest converged point.
double force_at_depth(const std::vector<double>& depth, const std::vector<double>& force, double target) {
  double d0 = 0, f0 = 0;
  for (std::size_t k = 0; k < depth.size(); ++k) {
    if (!std::isfinite(depth[k])) break;
    if (depth[k] >= target && depth[k] > d0) return f0 + (force[k] - f0) * (target - d0) / (depth[k] - d0);
    d0 = depth[k], f0 = force[k];
  }
  return std::nan("");
}

} // namespace

void deep_press(const std::filesystem::path& dir, Out& out) {
  const CsvTable t = CsvTable::read(dir / "deep_press.csv");
  const auto rows = [&t](const std::string& nu, const std::string& model) {
    return [&t, nu, model](std::size_t r) { return t.text(r, "poisson_ratio") == nu && t.text(r, "model") == model; };
  };
  const std::pair<const char*, const char*> materials[] = {{"0.3", "A"}, {"0.45", "B"}};
  for (const auto& [nu, tag] : materials) {
    std::vector<double> nh_depth, nh_force;
    for (const char* model : {"linear-p2", "springs", "neo-hookean-p2", "neo-hookean-p1", "svk-p1"}) {
      const std::vector<double> depth = column(t, "depth_ratio", rows(nu, model));
      const std::vector<double> force = column(t, "force", rows(nu, model));
      std::vector<double> pct{0.0}, mn{0.0}; // the plot's units: % of the layer, mN; every curve starts at rest
      for (std::size_t k = 0; k < depth.size(); ++k)
        if (std::isfinite(depth[k])) pct.push_back(100 * depth[k]), mn.push_back(1e3 * force[k]);
      out.files.emplace_back(std::string("deep_") + tag + "_" + model + ".dat", series("depth force", {pct, mn}));
      if (std::string(model) == "neo-hookean-p2") nh_depth = depth, nh_force = force;
    }
    // The gaps: a model's force at a depth against the neo-Hookean continuum's, in per cent.
    const auto gap = [&](const char* model, double d) {
      const double f = force_at_depth(column(t, "depth_ratio", rows(nu, model)), column(t, "force", rows(nu, model)), d);
      return 100 * (f / force_at_depth(nh_depth, nh_force, d) - 1);
    };
    const std::string T = tag;
    out.number("vtbDeepSpringsTen" + T, gap("springs", 0.1), 2);
    out.number("vtbDeepSpringsTwenty" + T, gap("springs", 0.2), 2);
    out.number("vtbDeepSpringsThirty" + T, gap("springs", 0.3), 2);
    out.number("vtbDeepLinearThirty" + T, gap("linear-p2", 0.3), 2);
    out.number("vtbDeepPOneThirty" + T, gap("neo-hookean-p1", 0.3), 2); // the discretisation's share
    std::vector<double> svk = column(t, "depth_ratio", rows(nu, "svk-p1")), levels = column(t, "level", rows(nu, "svk-p1"));
    double svk_last = 0;
    for (std::size_t k = 0; k < svk.size(); ++k)
      if (std::isfinite(svk[k])) svk_last = levels[k];
    out.number("vtbDeepSvkLast" + T, svk_last, 3);
    const std::vector<double> lf = column(t, "force", rows(nu, "linear-p2")), ld = column(t, "depth_ratio", rows(nu, "linear-p2"));
    out.number("vtbDeepFThirty" + T, lf.empty() ? std::nan("") : 1e3 * lf[0] * 0.3 / ld[0], 3); // linear: F30
  }
  out.number("vtbDeepNodes", column(t, "nodes", [](std::size_t) { return true; }).front(), 6);
}

} // namespace vtb::harness::paper
