#pragma once
/// \file
/// The viewer's OpenGL 3.3 core drawing: one shader program (colour per vertex, optional
/// two-sided shading by a per-vertex normal and the light: Lambert with an ambient floor, and a
/// white highlight on the faces that face the light, so that a solid's faces read apart even
/// where the colour map is dark) and one streamed vertex buffer. Vertex
/// data are built by the caller in a reused array of floats: x y z r g b nx ny nz.

#include <Eigen/Core>

#include <vector>

namespace vtb::viewer {

class GlDraw {
public:
  /// Compiles the program; needs a current OpenGL 3.3 core context. Throws std::runtime_error
  /// with the driver's log when a shader does not compile.
  GlDraw();
  ~GlDraw();
  GlDraw(const GlDraw&) = delete;
  GlDraw& operator=(const GlDraw&) = delete;

  enum class Mode { triangles, lines, points };
  /// Draws `floats.size() / 9` vertices.
  void draw(const std::vector<float>& floats, Mode mode, const Eigen::Matrix4d& mvp, bool lit, float size = 1.0f);
  /// The direction toward the light (scene space) for lit drawing; normalised here.
  void set_light(const Eigen::Vector3d& toward_light) { m_light = toward_light.normalized().cast<float>(); }

private:
  unsigned m_program = 0, m_vao = 0, m_vbo = 0;
  int m_mvp = -1, m_lit = -1, m_light_at = -1;
  Eigen::Vector3f m_light = Eigen::Vector3f(0.4f, 0.8f, 0.6f).normalized();
};

/// Appends one vertex to a GlDraw array.
inline void put(std::vector<float>& v, const Eigen::Vector3d& p, const float* rgb, const Eigen::Vector3d& n) {
  v.insert(v.end(), {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()), rgb[0], rgb[1],
                     rgb[2], static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z())});
}

} // namespace vtb::viewer
