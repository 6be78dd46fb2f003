#pragma once
/// \file
/// Notes on a scene's supports that a reader of the run line should see: in 3D the generated
/// and canonical meshes name their faces by the 2D plate's words (`bottom`, `top` are the y faces),
/// while every 3D scene of the repository takes z as up. A scene that fixes `bottom` and presses
/// along z is told which face it fixed (docs/scenes.md, "Faces by axis").

#include "vtb/problem/scene.hh"

#include <string>
#include <vector>

namespace vtb {

/// One note per fix or drive of a 3D scene (a load, drive, probe or plane with three entries, or a
/// generated box) that names the group `bottom` or `top` while a load, a drive or the device's
/// plane acts mostly along z; empty when no such support exists. A scene that means the y face can
/// name it `y_min` / `y_max`, which silences the note.
std::vector<std::string> support_face_notes(const Scene& scene);

} // namespace vtb
