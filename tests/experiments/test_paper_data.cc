// The paper's data step: LaTeX escaping, the CSV reader, numbers computed from the fixture
// reproduction, and the figure list that report.md and build_paper.sh share.
#include "vtb/base/input_error.hh"
#include "vtb/harness/csv_table.hh"
#include "vtb/harness/tex.hh"
#include "vtb/reproduction/paper_data.hh"
#include "vtb/reproduction/reproduce.hh"

#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>

namespace vtb {
namespace {

const std::filesystem::path kFixture = std::filesystem::path(VTB_SOURCE_DIR) / "tests/paper/fixture";

TEST(TexEscape, EverySpecialPrintsLiterally) {
  EXPECT_EQ(harness::tex_escape("a_b%c&d#e$f"), "a\\_b\\%c\\&d\\#e\\$f");
  EXPECT_EQ(harness::tex_escape("\\input{x}"), "\\textbackslash{}input\\{x\\}");
  EXPECT_EQ(harness::tex_escape("~^"), "\\textasciitilde{}\\textasciicircum{}");
  EXPECT_EQ(harness::tex_escape(std::string("a\nb\x01")), "ab"); // no line breaks or controls from data
  // Nothing a CSV can hold leaves a bare special: read the output as TeX would, skipping our
  // own commands (\\textbackslash{} ...) and escaped characters (\\_ ...); no special is left.
  const std::string all = harness::tex_escape("x_%&#$\\{}~^y");
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i] == '\\') {
      std::size_t j = i + 1;
      while (j < all.size() && std::isalpha(static_cast<unsigned char>(all[j]))) ++j;
      i = j == i + 1 ? i + 1 : (all.compare(j, 2, "{}") == 0 ? j + 1 : j - 1);
      continue;
    }
    EXPECT_EQ(std::string("_%&#$\\{}~^").find(all[i]), std::string::npos) << "bare '" << all[i] << "' in " << all;
  }
}

TEST(TexNumber, ReadableForms) {
  EXPECT_EQ(harness::tex_number(29.4321), "29.4");
  EXPECT_EQ(harness::tex_number(30019.8), "30020"); // not 3e+04
  EXPECT_EQ(harness::tex_number(1.94e-8), "\\ensuremath{1.94\\times10^{-8}}");
  EXPECT_EQ(harness::tex_number(std::nan("")), "n/a");
  EXPECT_THROW(harness::tex_macro("vtb1", "x"), std::logic_error); // TeX names are letters only
}

TEST(CsvTable, QuotedFieldsAndClearErrors) {
  const auto t = harness::CsvTable::parse("case,n\n\"a, \"\"b\"\"\",3\nc,nan\n", "t.csv");
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.text(0, "case"), "a, \"b\"");
  EXPECT_EQ(t.number(0, "n"), 3.0);
  EXPECT_TRUE(std::isnan(t.number(1, "n")));
  EXPECT_THROW(t.text(0, "missing"), InputError);
  try {
    harness::CsvTable::parse("a,b\n1,2,3\n", "bad.csv");
    FAIL() << "a row longer than the header was accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "bad.csv:2: 3 fields where the header has 2");
  }
  try {
    harness::CsvTable::parse("a\nx\n", "t.csv").number(0, "a");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "t.csv: row 2, column \"a\": \"x\" is not a number");
  }
}

std::map<std::string, std::string> data_files() {
  std::map<std::string, std::string> m;
  for (auto& [name, text] : reproduction::paper_data(kFixture)) m[name] = text;
  return m;
}

TEST(PaperData, NumbersComeFromTheFixture) {
  const auto files = data_files();
  const std::string& numbers = files.at("numbers.tex");
  // The fixture's 517-node, one-force row: filtered-full 29.4 us, implicit Euler 276 us.
  const auto t = harness::CsvTable::read(kFixture / "timing_table.csv");
  double full = 0, ie = 0;
  for (std::size_t r = 0; r < t.rows(); ++r)
    if (t.number(r, "nodes") == 517 && t.number(r, "forces") == 1) {
      if (t.text(r, "solver") == "filtered-full") full = t.number(r, "step_median_us");
      if (t.text(r, "solver") == "implicit-euler") ie = t.number(r, "step_median_us");
    }
  EXPECT_NE(numbers.find("\\newcommand\\vtbFullStepUs{" + harness::tex_number(full) + "}"), std::string::npos);
  EXPECT_NE(numbers.find("\\newcommand\\vtbSpeedupIE{" + harness::tex_number(ie / full, 2) + "}"), std::string::npos);
  // Every figure's series exists; the Pareto front is non-empty and sorted by cost.
  for (const char* f : {"timing_rows.tex", "calibration_rows.tex", "pareto.dat", "courant.dat", "creep.dat",
                        "haptics_hist.dat", "haptics_trace.dat", "fig3_fem_2.dat", "scaling_3_filtered-full.dat"})
    EXPECT_TRUE(files.count(f)) << f;
  EXPECT_GT(std::count(files.at("pareto.dat").begin(), files.at("pareto.dat").end(), '\n'), 1);
}

TEST(PaperData, FidelityTableComesFromTheFixture) {
  // The worst fitted error against P1 on the mesh, the fitted springs', Lloyd's and P1's
  // against the continuum, are the maxima of the CSV's columns (in percent); the cases where P1
  // misses the continuum by more than 5 % are counted, and those where the fitted springs are
  // closer to it; every case gets a row.
  const auto files = data_files();
  const std::string& numbers = files.at("numbers.tex");
  const auto t = harness::CsvTable::read(kFixture / "fidelity.csv");
  double fitted = 0, lloyd = 0, fitted_continuum = 0, mesh_fem = 0;
  int locking = 0, closer = 0;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    const double e = 100 * t.number(r, "displacement_error");
    const double c = 100 * t.number(r, "continuum_error"), p1 = 100 * t.number(r, "mesh_fem_continuum_error");
    if (t.text(r, "springs") == "fitted") {
      fitted = std::max(fitted, e);
      fitted_continuum = std::max(fitted_continuum, c);
      locking += p1 > 5;
      closer += p1 > 5 && c < p1;
    }
    if (t.text(r, "springs") == "lloyd") lloyd = std::max(lloyd, c);
    mesh_fem = std::max(mesh_fem, p1);
    EXPECT_NE(files.at("fidelity_rows.tex").find(t.text(r, "case") + " & "), std::string::npos);
  }
  EXPECT_NE(numbers.find("\\newcommand\\vtbFittedWorst{" + harness::tex_number(fitted, 2) + "}"), std::string::npos);
  EXPECT_NE(numbers.find("\\newcommand\\vtbLloydWorst{" + harness::tex_number(lloyd, 2) + "}"), std::string::npos);
  EXPECT_NE(numbers.find("\\newcommand\\vtbFittedWorstContinuum{" + harness::tex_number(fitted_continuum, 2) + "}"),
            std::string::npos);
  EXPECT_NE(numbers.find("\\newcommand\\vtbMeshFemWorst{" + harness::tex_number(mesh_fem, 2) + "}"), std::string::npos);
  EXPECT_NE(numbers.find("\\newcommand\\vtbLockingCases{" + harness::tex_number(locking, 3) + "}"), std::string::npos);
  EXPECT_NE(numbers.find("\\newcommand\\vtbFittedCloserCases{" + harness::tex_number(closer, 3) + "}"),
            std::string::npos);
  EXPECT_GT(locking, 0) << "the fixture holds cases where P1 on the mesh locks";
  EXPECT_EQ(std::count(files.at("fidelity_rows.tex").begin(), files.at("fidelity_rows.tex").end(), '\n'),
            static_cast<long>(t.rows() / 3));
}

TEST(PaperData, FitCostComesFromTheFixture) {
  // The sentence on the fit's cost names every slab of spring_fit.csv with its seconds and
  // nodes as the CSV has them, and the held-out error of the largest; with no rows (a build
  // without CGAL's meshers) the sentence is empty.
  const auto files = data_files();
  const std::string& numbers = files.at("numbers.tex");
  const auto t = harness::CsvTable::read(kFixture / "spring_fit.csv");
  ASSERT_GT(t.rows(), 1U) << "the fixture holds a ladder";
  std::size_t largest = 0;
  for (std::size_t r = 1; r < t.rows(); ++r)
    if (t.number(r, "nodes") > t.number(largest, "nodes")) largest = r;
  const auto at = numbers.find("\\newcommand\\vtbFitCost{");
  ASSERT_NE(at, std::string::npos);
  const std::string sentence = numbers.substr(at, numbers.find('\n', at) - at);
  for (std::size_t r = 0; r < t.rows(); ++r) {
    const std::string part = harness::tex_number(t.number(r, "fit_seconds"), 2) + "~s at " +
                             harness::tex_number(t.number(r, "nodes")) + " nodes";
    EXPECT_NE(sentence.find(part), std::string::npos) << part << " in " << sentence;
  }
  const std::string held = harness::tex_number(100 * t.number(largest, "validation_error"), 2) + "\\,\\% at " +
                           harness::tex_number(t.number(largest, "nodes")) + " nodes";
  EXPECT_NE(sentence.find(held), std::string::npos) << held << " in " << sentence;
}

TEST(PaperData, DeepPressRefinementComesFromTheFixture) {
  // How far one refinement moves the neo-Hookean reference: the refined solve's depth at 0.5 F30
  // against the path's on the mesh at that level, in per cent, per material (A: nu 0.3, B: 0.45).
  const std::string numbers = data_files().at("numbers.tex");
  const auto t = harness::CsvTable::read(kFixture / "deep_press.csv");
  for (const auto& [nu, tag] : {std::pair{"0.3", "A"}, std::pair{"0.45", "B"}}) {
    double mesh = 0, refined = 0;
    for (std::size_t r = 0; r < t.rows(); ++r)
      if (t.text(r, "poisson_ratio") == nu && t.number(r, "level") == 0.5) {
        if (t.text(r, "model") == "neo-hookean-p2") mesh = t.number(r, "depth");
        if (t.text(r, "model") == "neo-hookean-p2-refined") refined = t.number(r, "depth");
      }
    ASSERT_GT(mesh, 0) << nu;
    ASSERT_GT(refined, 0) << "the fixture holds the refined solve for nu " << nu;
    const std::string macro = std::string("\\newcommand\\vtbDeepRefinedHalf") + tag + "{" +
                              harness::tex_number(100 * (refined / mesh - 1), 2) + "}";
    EXPECT_NE(numbers.find(macro), std::string::npos) << macro;
  }
}

TEST(PaperData, DeepPressVolumeNetworksComeFromTheFixture) {
  // The networks with the stable cells (springs-fitted-stable) and with the volume per node
  // (springs-fitted-nodal): the most cells inverted at once per material is the fixture's
  // largest inverted_cells, and the curve holds every finite depth of the fixture (and the rest
  // point the plot starts from).
  const auto files = data_files();
  const std::string& numbers = files.at("numbers.tex");
  const auto t = harness::CsvTable::read(kFixture / "deep_press.csv");
  for (const auto& [model, name] :
       {std::pair{"springs-fitted-stable", "Stable"}, std::pair{"springs-fitted-nodal", "Nodal"}})
    for (const auto& [nu, tag] : {std::pair{"0.3", "A"}, std::pair{"0.45", "B"}}) {
      double inverted = -1;
      long points = 1;
      for (std::size_t r = 0; r < t.rows(); ++r)
        if (t.text(r, "poisson_ratio") == nu && t.text(r, "model") == model) {
          inverted = std::max(inverted, t.number(r, "inverted_cells"));
          points += std::isfinite(t.number(r, "depth_ratio"));
        }
      ASSERT_GE(inverted, 0) << "the fixture holds " << model << " for nu " << nu;
      const std::string macro =
          std::string("\\newcommand\\vtbDeep") + name + "Inverted" + tag + "{" + harness::tex_number(inverted, 6) + "}";
      EXPECT_NE(numbers.find(macro), std::string::npos) << macro;
      const std::string& curve = files.at(std::string("deep_") + tag + "_" + model + ".dat");
      EXPECT_EQ(std::count(curve.begin(), curve.end(), '\n'), points + 1) << "a header and one line a point";
    }
}

TEST(PaperData, TransientTableComesFromTheFixture) {
  // One row per dt (three in the fixture), each starting with dt in ms and holding the tensor
  // filter's tip error in percent as the CSV has it.
  const auto files = data_files();
  const std::string& rows = files.at("transient_rows.tex");
  EXPECT_EQ(std::count(rows.begin(), rows.end(), '\n'), 3);
  const auto t = harness::CsvTable::read(kFixture / "transient.csv");
  for (std::size_t r = 0; r < t.rows(); ++r)
    if (t.text(r, "solver") == "filtered-tensor") {
      const std::string row = harness::tex_number(1000 * t.number(r, "dt")) + " & ";
      const auto at = rows.find(row);
      ASSERT_NE(at, std::string::npos) << row;
      EXPECT_NE(rows.find(" & " + harness::tex_number(100 * t.number(r, "tip_error"), 2) + " & ", at),
                std::string::npos);
    }
}

TEST(PaperData, LogLogSlopeRecoversAPowerLaw) {
  // The fitted order (convergence) and exponent (scaling): y = 3 x^1.5 exactly, plus points
  // that a log axis cannot hold (x or y <= 0), which the fit skips.
  const std::vector<double> x = {1, 2, 4, 8, 0, 5}, y = {3, 3 * std::pow(2, 1.5), 3 * 8.0, 3 * std::pow(8, 1.5), 1, -1};
  EXPECT_NEAR(reproduction::paper::loglog_slope(x, y), 1.5, 1e-12);
  EXPECT_TRUE(std::isnan(reproduction::paper::loglog_slope({1}, {1})));
}

TEST(PaperData, MissingFileIsOneClearError) {
  try {
    reproduction::paper_data(kFixture / "fig3");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("meta.csv: cannot read"), std::string::npos) << e.what();
  }
}

TEST(ReportFigures, EachHasItsPgfplotsSource) {
  for (const auto& f : reproduction::kReportFigures)
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(VTB_SOURCE_DIR) / "paper/figures" /
                                        (std::string(f.file) + ".tex")))
        << f.file;
  std::size_t sources = 0;
  for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(VTB_SOURCE_DIR) / "paper/figures"))
    sources += e.path().extension() == ".tex";
  EXPECT_EQ(sources, std::size(reproduction::kReportFigures)) << "a figure the report does not show, or the reverse";
}

} // namespace
} // namespace vtb
