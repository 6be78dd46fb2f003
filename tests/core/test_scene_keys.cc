// docs/scenes.md lists every scene key: this test asks the parser for the keys it accepts,
// table by table (an unknown key far from all of them makes it list them), and compares them
// with the page's tables. A key added to the parser and not to the page fails here.
#include "vtb/base/input_error.hh"
#include "vtb/problem/scene.hh"

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

namespace vtb {
namespace {

const std::string kBogus = "zzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzz = 1";

/// A scene with every table; `at` names the table that gets the bogus key.
std::string scene_with_bogus_key(const std::string& at) {
  auto in = [&](const std::string& table) { return at == table ? kBogus + "\n" : std::string(); };
  return in("") + "[scene]\nduration = 1.0\noutput_interval = 0.1\n" + in("[scene]") + "[mesh]\n" + in("[mesh]") +
         "generate = { shape = \"rectangle\", size = [0.2, 0.05], divisions = [4, 2]" +
         (at == "[mesh].generate" ? ", zzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzz = 1" : "") + " }\n" +
         "[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.3\ndensity = 1000.0\n" + in("[material]") +
         "[[fix]]\ngroup = \"left\"\n" + in("[[fix]]") + "[[load]]\ngroup = \"right\"\ntotal_force = [1.0, 0.0]\n" +
         in("[[load]]") + "[[drive]]\npoint = [0.2, 0.05]\ndisplacement = [0.0, 0.001]\n" + in("[[drive]]") +
         "[initial]\nvelocity = [0.0, 0.0]\n" + in("[initial]") + "[[probe]]\nname = \"tip\"\npoint = [0.2, 0.0]\n" +
         in("[[probe]]") + "[solver]\nkind = \"filtered\"\n" + in("[solver]") + "[haptics]\nmax_force = 4.0\n" +
         in("[haptics]") + "[haptics.hand]\nwaypoints = [[0.05, 0.08]]\nduration = 1.0\ngrip_stiffness = 2000.0\n" +
         in("[haptics.hand]") +
         "[[haptics.probe]]\nwaypoints = [[0.05, 0.08]]\nduration = 1.0\ngrip_stiffness = 2000.0\n" +
         in("[[haptics.probe]]") + "[haptics.plane]\norigin = [0.0, 0.0, 0.0]\n" + in("[haptics.plane]");
}

std::set<std::string> parser_keys(const std::string& table) {
  try {
    parse_scene(scene_with_bogus_key(table), "keys.toml", ".");
  } catch (const InputError& e) {
    const std::string msg = e.what();
    const auto at = msg.find("; known keys:");
    if (at == std::string::npos) ADD_FAILURE() << table << ": " << msg;
    std::istringstream is(msg.substr(at + 13));
    std::set<std::string> keys;
    for (std::string k; is >> k;) keys.insert(k);
    return keys;
  }
  ADD_FAILURE() << table << ": the bogus key was accepted";
  return {};
}

/// The page's keys per table: the first column's `names` of the tables under each heading;
/// a heading names its table in backticks (the first one), "Top level" is "".
std::map<std::string, std::set<std::string>> page_keys() {
  std::ifstream f(std::filesystem::path(VTB_SOURCE_DIR) / "docs" / "scenes.md");
  EXPECT_TRUE(f.good());
  std::map<std::string, std::set<std::string>> out;
  std::string table, line;
  const std::regex heading(R"(^#+ (?:`([^`]+)`|Top level))"), name(R"(`([a-z_]+)`)");
  while (std::getline(f, line)) {
    std::smatch m;
    if (std::regex_search(line, m, heading) && line.rfind("# Scene files", 0) != 0) {
      table = m[1].matched ? m[1].str() : "";
      continue;
    }
    if (line.rfind("| `", 0) != 0) continue;
    const std::string first = line.substr(0, line.find('|', 1));
    for (auto it = std::sregex_iterator(first.begin(), first.end(), name); it != std::sregex_iterator(); ++it)
      out[table].insert((*it)[1].str());
  }
  return out;
}

TEST(SceneKeys, DocsScenesListsExactlyTheKeysTheParserAccepts) {
  const auto page = page_keys();
  for (const std::string table :
       {"", "[scene]", "[mesh]", "[mesh].generate", "[material]", "[[fix]]", "[[load]]", "[[drive]]", "[initial]",
        "[[probe]]", "[solver]", "[haptics]", "[haptics.hand]", "[haptics.plane]"}) {
    const std::set<std::string> parser = parser_keys(table);
    ASSERT_FALSE(parser.empty()) << table;
    const auto it = page.find(table);
    ASSERT_NE(it, page.end()) << "docs/scenes.md has no section for " << (table.empty() ? "the top level" : table);
    EXPECT_EQ(it->second, parser) << "docs/scenes.md and the parser disagree on the keys of "
                                  << (table.empty() ? "the top level" : table);
  }
  // [[haptics.probe]] takes the keys of [haptics.hand] (one section documents both).
  EXPECT_EQ(parser_keys("[[haptics.probe]]"), parser_keys("[haptics.hand]"));
}

} // namespace
} // namespace vtb
