#pragma once
/// \file
/// `vtb paper-data REPRODUCE_DIR OUT_DIR`: the reproduction's CSV files turned into what the
/// LaTeX paper reads (paper/README.md): numbers.tex (one macro per number a caption or the text
/// states), timing_rows.tex and calibration_rows.tex (table rows), and whitespace-separated
/// .dat series for pgfplots. Every string from the data is escaped (tex_escape), so the paper
/// runs no TeX code from a CSV; every number is computed here from the CSVs, none typed.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace vtb::reproduction {

/// The files, by name, that write_paper_data writes (for tests).
std::vector<std::pair<std::string, std::string>> paper_data(const std::filesystem::path& reproduce_dir);

/// Writes paper_data(reproduce_dir) into out_dir, all or nothing.
void write_paper_data(const std::filesystem::path& reproduce_dir, const std::filesystem::path& out_dir);

namespace paper {
/// Least-squares slope of log y against log x over the points with x, y > 0 (NaN if fewer
/// than two): the fitted order of convergence and exponent of scaling the paper states.
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y);
} // namespace paper

} // namespace vtb::reproduction
