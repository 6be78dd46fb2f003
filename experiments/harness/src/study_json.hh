#pragma once
/// \file
/// A study's row as JSON, every double exact (hexadecimal): the gather of an MPI study on rank 0
/// (study.cc) and study.json, which vtb merge reads back (study_output.cc).

#include "vtb/harness/study.hh"

#include <nlohmann/json.hpp>

namespace vtb::harness {

nlohmann::json row_json(const StudyRow& r);
StudyRow row_from_json(const nlohmann::json& j);

} // namespace vtb::harness
