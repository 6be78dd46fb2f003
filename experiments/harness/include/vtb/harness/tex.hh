#pragma once
/// \file
/// Text and numbers from data, made safe for LaTeX: whatever a scene or case name holds
/// (_ % & # $ \ { } ~ ^) prints literally and cannot run TeX code.

#include <string>
#include <string_view>

namespace vtb::harness {

/// Escapes the ten LaTeX specials; drops control characters.
std::string tex_escape(std::string_view text);

/// A number as the paper prints it: `digits` significant digits, "n/a" for NaN.
std::string tex_number(double value, int digits = 3);

/// A number as pgfplots parses it (plain or 1e-05 form, 8 digits), for coordinates.
std::string plain_number(double value);

/// vtb's figure look as LaTeX (experiments/harness/tex/plot_styles.tex): fonts, pgfplots and
/// one style per solver, for the paper's figures and `vtb study`'s plot alike.
std::string_view plot_styles();

/// \newcommand\NAME{VALUE}\n, NAME letters only (checked: a bad name is a programming error).
std::string tex_macro(const std::string& name, const std::string& value);

} // namespace vtb::harness
