#include "gl_draw.hh"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <stdexcept>
#include <string>

namespace vtb::viewer {
namespace {

const char* kVertex = R"(#version 330 core
layout(location = 0) in vec3 pos;
layout(location = 1) in vec3 col;
layout(location = 2) in vec3 nrm;
uniform mat4 mvp;
uniform int lit;
uniform vec3 light;
out vec3 colour;
void main() {
  gl_Position = mvp * vec4(pos, 1.0);
  colour = col;
  if (lit != 0) {
    float d = abs(dot(normalize(nrm), light));
    colour = col * (0.30 + 0.70 * d) + vec3(0.24) * d * d;
  }
}
)";

const char* kFragment = R"(#version 330 core
in vec3 colour;
out vec4 frag;
void main() { frag = vec4(colour, 1.0); }
)";

unsigned compile(GLenum kind, const char* src) {
  const unsigned s = glCreateShader(kind);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  int ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    throw std::runtime_error(std::string("vtb view: shader does not compile: ") + log);
  }
  return s;
}

} // namespace

GlDraw::GlDraw() {
  const unsigned vs = compile(GL_VERTEX_SHADER, kVertex), fs = compile(GL_FRAGMENT_SHADER, kFragment);
  m_program = glCreateProgram();
  glAttachShader(m_program, vs);
  glAttachShader(m_program, fs);
  glLinkProgram(m_program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  int ok = 0;
  glGetProgramiv(m_program, GL_LINK_STATUS, &ok);
  if (!ok) throw std::runtime_error("vtb view: shader program does not link");
  m_mvp = glGetUniformLocation(m_program, "mvp");
  m_lit = glGetUniformLocation(m_program, "lit");
  m_light_at = glGetUniformLocation(m_program, "light");
  glGenVertexArrays(1, &m_vao);
  glGenBuffers(1, &m_vbo);
  glBindVertexArray(m_vao);
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  const GLsizei stride = 9 * sizeof(float);
  for (unsigned a = 0; a < 3; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(a * 3 * sizeof(float)));
  }
  glBindVertexArray(0);
}

GlDraw::~GlDraw() {
  glDeleteBuffers(1, &m_vbo);
  glDeleteVertexArrays(1, &m_vao);
  glDeleteProgram(m_program);
}

void GlDraw::draw(const std::vector<float>& v, Mode mode, const Eigen::Matrix4d& mvp, bool lit, float size) {
  if (v.empty()) return;
  glUseProgram(m_program);
  const Eigen::Matrix4f m = mvp.cast<float>();
  glUniformMatrix4fv(m_mvp, 1, GL_FALSE, m.data()); // Eigen is column-major, as GL expects
  glUniform1i(m_lit, lit ? 1 : 0);
  glUniform3f(m_light_at, m_light.x(), m_light.y(), m_light.z());
  glBindVertexArray(m_vao);
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(v.size() * sizeof(float)), v.data(), GL_STREAM_DRAW);
  const auto n = static_cast<GLsizei>(v.size() / 9);
  if (mode == Mode::triangles) glDrawArrays(GL_TRIANGLES, 0, n);
  if (mode == Mode::lines) {
    glLineWidth(size);
    glDrawArrays(GL_LINES, 0, n);
  }
  if (mode == Mode::points) {
    glPointSize(size);
    glDrawArrays(GL_POINTS, 0, n);
  }
  glBindVertexArray(0);
}

} // namespace vtb::viewer
