#pragma once
/// \file
/// The pieces of `paper_data` (internal): each reads one part of a reproduction and adds its
/// files and macros to the Out.

#include "vtb/harness/csv_table.hh"
#include "vtb/reproduction/paper_data.hh"

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace vtb::reproduction::paper {
using namespace vtb::harness; // a private header of the reproduction: the harness is its base

struct Out {
  std::vector<std::pair<std::string, std::string>> files; ///< name, text
  std::string macros;                                     ///< numbers.tex
  void macro(const std::string& name, const std::string& value);
  void number(const std::string& name, double value, int digits = 3);
  /// NAME for text and NAMERaw for plot coordinates.
  void number_and_raw(const std::string& name, double value, int digits = 3);
};

/// Column values of the rows where `keep` holds, in file order.
template <class Keep> std::vector<double> column(const CsvTable& t, const std::string& name, Keep keep) {
  std::vector<double> v;
  for (std::size_t r = 0; r < t.rows(); ++r)
    if (keep(r)) v.push_back(t.number(r, name));
  return v;
}

/// A plot's data file: the header line, then one row per index of the columns.
std::string series(const std::string& header, const std::vector<std::vector<double>>& columns);

void timing(const std::filesystem::path& dir, Out& out);        // timing_rows.tex, calibration_rows.tex
void fidelity(const std::filesystem::path& dir, Out& out);      // fidelity_rows.tex, vtbLloydWorst, vtbFittedWorst
void fit_cost(const std::filesystem::path& dir, Out& out);      // vtbFitCost (spring_fit.csv)
void transient(const std::filesystem::path& dir, Out& out);     // transient_rows.tex
void accuracy(const std::filesystem::path& dir, Out& out);      // acc_*.dat, pareto.dat, conv_*.dat, decomp_*.dat
void stability(const std::filesystem::path& dir, Out& out);     // stab_*.dat, courant.dat
void fig3(const std::filesystem::path& dir, Out& out);          // fig3_*.dat
void creep_scaling(const std::filesystem::path& dir, Out& out); // creep.dat, scaling_*.dat
void haptics(const std::filesystem::path& dir, Out& out);       // haptics_hist.dat, haptics_trace.dat
void multirate(const std::filesystem::path& dir, Out& out);     // multirate_trace.dat
void tip_force(const std::filesystem::path& dir, Out& out);     // tip_<mesh>_<tip|point>.dat, tip_anchor.dat
void deep_press(const std::filesystem::path& dir, Out& out);    // deep_<nu>_<model>.dat, vtbDeep* (gaps to neo-Hookean)

} // namespace vtb::reproduction::paper
