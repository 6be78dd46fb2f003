// A 3D scene that fixes "bottom" (the y = 0 face of the generated and canonical meshes) while it
// presses along z is told which face it fixed; one that names the face by axis, or fixes the
// y face and pushes along y, or is a plate, is not.
#include "vtb/problem/support_notes.hh"

#include <gtest/gtest.h>

namespace vtb {
namespace {

std::string box_scene(const std::string& fix_group, const std::string& force) {
  return "[scene]\nname = \"block\"\nduration = 0.1\noutput_interval = 0.01\n"
         "[mesh]\ngenerate = { shape = \"box\", size = [0.04, 0.04, 0.02], divisions = [4, 4, 2] }\n"
         "[material]\nyoung_modulus = 5.0e3\npoisson_ratio = 0.3\ndensity = 1000.0\n"
         "[[fix]]\nname = \"base\"\ngroup = \"" +
         fix_group + "\"\n[[load]]\nname = \"press\"\npoint = [0.02, 0.02, 0.02]\ntotal_force = [" + force + "]\n";
}

std::vector<std::string> notes_of(const std::string& text) {
  return support_face_notes(parse_scene(text, "block.toml", "."));
}

TEST(SupportNotes, FixingBottomWhilePressingAlongZIsTold) {
  const auto notes = notes_of(box_scene("bottom", "0.0, 0.0, -0.1"));
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("[[fix]] base names group \"bottom\""), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("y_min"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("z_min"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("[[load]] press"), std::string::npos) << notes[0];
  const auto top = notes_of(box_scene("top", "0.0, 0.0, -0.1"));
  ASSERT_EQ(top.size(), 1u);
  EXPECT_NE(top[0].find("z_max"), std::string::npos) << top[0];
}

TEST(SupportNotes, NamingTheFaceByAxisOrPushingAlongYIsNotTold) {
  EXPECT_TRUE(notes_of(box_scene("z_min", "0.0, 0.0, -0.1")).empty());
  EXPECT_TRUE(notes_of(box_scene("y_min", "0.0, 0.0, -0.1")).empty());
  EXPECT_TRUE(notes_of(box_scene("front", "0.0, 0.0, -0.1")).empty());
  EXPECT_TRUE(notes_of(box_scene("bottom", "0.0, -0.1, 0.0")).empty());
}

TEST(SupportNotes, ADevicePlaneHoldingZCountsAsActingAlongZ) {
  const std::string scene = box_scene("bottom", "0.0, -0.1, 0.0") +
                            "[solver]\nkind = \"filtered\"\n[haptics]\n[haptics.plane]\norigin = [0.0, 0.02, 0.0]\n"
                            "x_axis = [1.0, 0.0, 0.0]\ny_axis = [0.0, 0.0, 1.0]\n";
  const auto notes = notes_of(scene);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("the device"), std::string::npos) << notes[0];
}

TEST(SupportNotes, APlateIsNeverTold) {
  const std::string plate = "[scene]\nname = \"plate\"\nduration = 0.1\noutput_interval = 0.01\n"
                            "[mesh]\ngenerate = { shape = \"rectangle\", size = [0.2, 0.05], divisions = [4, 2] }\n"
                            "[material]\nyoung_modulus = 5.0e4\npoisson_ratio = 0.3\ndensity = 1000.0\n"
                            "[[fix]]\ngroup = \"bottom\"\n[[load]]\ngroup = \"top\"\ntotal_force = [0.0, -0.1]\n";
  EXPECT_TRUE(notes_of(plate).empty());
}

} // namespace
} // namespace vtb
