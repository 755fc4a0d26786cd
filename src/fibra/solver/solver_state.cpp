#include "fibra/solver/solver_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <type_traits>

#include <fmt/core.h>

#include "fibra/core/error.hpp"
#include "fibra/core/file.hpp"
#include "fibra/model/model.hpp"

namespace fibra {
namespace {

// Layout (little-endian, as the machine writes it): the magic line, a version, then the fields
// in the order below, then the end mark (a truncated file misses it).
constexpr char kMagic[] = "fibra state\n";
constexpr std::uint32_t kVersion = 2;  // 2: test_drag
constexpr char kEnd[] = "end of state\n";

// Appends the fields' bytes to a buffer (the file is then written at once, atomically).
class Out {
 public:
  explicit Out(std::string& s) : m_s(s) {}
  template <typename T>
  void put(const T& v) {
    static_assert(std::is_arithmetic_v<T>);
    bytes(&v, sizeof(T));
  }
  void put(const std::string& v) {
    put(static_cast<std::uint64_t>(v.size()));
    bytes(v.data(), v.size());
  }
  void put(const Vec3& v) { bytes(v.data(), 3 * sizeof(double)); }
  void put(const VecX& v) {
    put(static_cast<std::uint64_t>(v.size()));
    bytes(v.data(), static_cast<size_t>(v.size()) * sizeof(double));
  }
  void put(const std::vector<double>& v) {
    put(static_cast<std::uint64_t>(v.size()));
    bytes(v.data(), v.size() * sizeof(double));
  }
  void bytes(const void* p, size_t n) { m_s.append(static_cast<const char*>(p), n); }

 private:
  std::string& m_s;
};

class In {
 public:
  In(std::ifstream& s, const std::string& path) : m_s(s), m_path(path) {
    m_s.seekg(0, std::ios::end);
    m_size = static_cast<std::uint64_t>(std::max<std::streamoff>(m_s.tellg(), 0));
    m_s.seekg(0, std::ios::beg);
  }
  template <typename T>
  T get() {
    static_assert(std::is_arithmetic_v<T>);
    T v{};
    read(&v, sizeof(T));
    return v;
  }
  // A count of items of at least `bytes` bytes each, bounded by `limit` and by what is left of
  // the file, so that a corrupt or truncated file fails with a message before anything of
  // that size is allocated.
  std::uint64_t count(std::uint64_t limit, std::uint64_t bytes) {
    const auto n = get<std::uint64_t>();
    if (n > limit) bad(fmt::format("a count of {} (at most {} expected): the file is corrupt", n, limit));
    const std::uint64_t left = m_size - std::min<std::uint64_t>(m_size, static_cast<std::uint64_t>(m_s.tellg()));
    if (n > left / bytes)
      bad(fmt::format("the file ends early: {} items of {} bytes announced, {} bytes left (truncated or corrupt)", n,
                      bytes, left));
    return n;
  }
  std::string text() {
    std::string v(count(1u << 20, 1), '\0');
    read(v.data(), v.size());
    return v;
  }
  Vec3 vec3() {
    Vec3 v;
    read(v.data(), 3 * sizeof(double));
    return v;
  }
  VecX vecx(std::uint64_t limit) {
    VecX v(static_cast<Index>(count(limit, sizeof(double))));
    read(v.data(), static_cast<size_t>(v.size()) * sizeof(double));
    return v;
  }
  std::vector<double> doubles(std::uint64_t limit) {
    std::vector<double> v(count(limit, sizeof(double)));
    read(v.data(), v.size() * sizeof(double));
    return v;
  }
  void read(void* p, size_t n) {
    if (!m_s.read(static_cast<char*>(p), static_cast<std::streamsize>(n)))
      bad("the file ends early (truncated: was its run stopped while writing it?)");
  }
  [[noreturn]] void bad(const std::string& why) const { throw InputError(m_path, "(file)", why); }

 private:
  std::ifstream& m_s;
  std::string m_path;
  std::uint64_t m_size = 0;  // the file's size [bytes]
};

void put_particle(Out& o, const Particle& p) {
  o.put(static_cast<std::int64_t>(p.element));
  o.put(p.eta);
  o.put(p.xi1);
  o.put(p.xi2);
}

Particle get_particle(In& in) {
  Particle p;
  p.element = in.get<std::int64_t>();
  p.eta = in.get<double>();
  p.xi1 = in.get<double>();
  p.xi2 = in.get<double>();
  return p;
}

}  // namespace

ModelFingerprint fingerprint(const Model& model, Index bindings) {
  return {model.num_dofs(), static_cast<std::int64_t>(model.elements.size()),
          static_cast<std::int64_t>(model.bodies.size()), bindings};
}

void write_state_file(const std::string& path, const SolverState& s) {
  std::string buffer;
  {
    Out o(buffer);
    o.bytes(kMagic, sizeof(kMagic) - 1);
    o.put(kVersion);
    o.put(s.model.dofs);
    o.put(s.model.elements);
    o.put(s.model.bodies);
    o.put(s.model.bindings);
    o.put(s.reference);
    o.put(s.step);
    o.put(static_cast<std::int32_t>(s.steps_done));
    o.put(s.q);
    o.put(s.bodies);
    o.put(static_cast<std::uint64_t>(s.contacts.size()));
    for (const ContactElement& c : s.contacts) {
      put_particle(o, c.a);
      put_particle(o, c.b);
      o.put(c.normal);
      o.put(c.law.stiffness);
      o.put(c.law.regularization);
      o.put(static_cast<std::int32_t>(c.zone));
      o.put(static_cast<std::uint8_t>(c.fresh));
      o.put(static_cast<std::uint8_t>(c.prescribed));
      o.put(c.offset);
      o.put(c.friction_normal);
      o.put(c.friction_previous);
      o.put(c.separation_previous);
    }
    o.put(s.force_end);
    o.put(static_cast<std::uint64_t>(s.moments.size()));
    for (const auto& [node, m] : s.moments) {
      o.put(static_cast<std::int64_t>(node));
      o.put(m.first);
      o.put(m.second);
    }
    o.put(static_cast<std::uint64_t>(s.disp.size()));
    for (const auto& [dof, d] : s.disp) {
      o.put(static_cast<std::int64_t>(dof));
      o.put(d.first);
      o.put(d.second);
    }
    o.put(s.test_drag);
    o.bytes(kEnd, sizeof(kEnd) - 1);
  }
  write_file_atomic(path, buffer);
}

SolverState read_state_file(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path, "(file)", "cannot open the state file");
  In in(file, path);
  char magic[sizeof(kMagic) - 1];
  if (!file.read(magic, sizeof(magic)) || std::memcmp(magic, kMagic, sizeof(magic)) != 0)
    in.bad("not a fibra state file (state.bin of a result directory expected)");
  const auto version = in.get<std::uint32_t>();
  if (version < 1 || version > kVersion)
    in.bad(fmt::format("state file version {}, this fibra reads versions 1 to {}: run the case again", version,
                       kVersion));
  SolverState s;
  s.model.dofs = in.get<std::int64_t>();
  s.model.elements = in.get<std::int64_t>();
  s.model.bodies = in.get<std::int64_t>();
  s.model.bindings = in.get<std::int64_t>();
  const std::uint64_t dofs = static_cast<std::uint64_t>(std::max<std::int64_t>(s.model.dofs, 0));
  s.reference = in.vecx(dofs);
  s.step = in.text();
  s.steps_done = in.get<std::int32_t>();
  s.q = in.vecx(dofs);
  s.bodies = in.doubles(std::uint64_t{1} << 40);
  // Bytes per item as written: two particles (8 + 3 * 8), the normal, stiffness,
  // regularization, zone, two flags, offset, friction normal and two vectors.
  const std::uint64_t n = in.count(std::uint64_t{1} << 40, 2 * 32 + 24 + 16 + 4 + 2 + 16 + 48);
  s.contacts.resize(n);
  for (ContactElement& c : s.contacts) {
    c.a = get_particle(in);
    c.b = get_particle(in);
    if (c.a.element < 0 || c.a.element >= s.model.elements || c.b.element < 0 || c.b.element >= s.model.elements)
      in.bad("a contact element refers to a beam element out of range: the file is corrupt");
    c.normal = in.vec3();
    c.law.stiffness = in.get<double>();
    c.law.regularization = in.get<double>();
    c.zone = in.get<std::int32_t>();
    c.fresh = in.get<std::uint8_t>() != 0;
    c.prescribed = in.get<std::uint8_t>() != 0;
    c.offset = in.get<double>();
    c.friction_normal = in.get<double>();
    c.friction_previous = in.vec3();
    c.separation_previous = in.vec3();
  }
  s.force_end = in.vecx(dofs);
  const std::uint64_t moments = in.count(dofs, 8 + 2 * 24);
  for (std::uint64_t k = 0; k < moments; ++k) {
    const auto node = in.get<std::int64_t>();
    const Vec3 a = in.vec3(), b = in.vec3();
    s.moments[node] = {a, b};
  }
  const std::uint64_t disp = in.count(dofs, 8 + 2 * 8);
  for (std::uint64_t k = 0; k < disp; ++k) {
    const auto dof = in.get<std::int64_t>();
    const double a = in.get<double>(), b = in.get<double>();
    s.disp[dof] = {a, b};
  }
  if (version >= 2) {
    s.test_drag = in.get<double>();
    if (!std::isfinite(s.test_drag) || s.test_drag < 0.0) in.bad("a negative or undefined test drag: the file is corrupt");
  }
  char end[sizeof(kEnd) - 1];
  in.read(end, sizeof(end));
  if (std::memcmp(end, kEnd, sizeof(end)) != 0) in.bad("no end mark: the file is corrupt");
  if (s.q.size() != s.model.dofs || s.reference.size() != s.model.dofs || s.force_end.size() != s.model.dofs)
    in.bad("its vectors do not match its number of dofs: the file is corrupt");
  return s;
}

void check_state_fits(const SolverState& s, const Model& model, Index bindings, const std::string& file) {
  const ModelFingerprint here = fingerprint(model, bindings);
  if (!(s.model == here))
    throw InputError(file, "(file)",
                     fmt::format("the state belongs to another model ({} dofs, {} elements, {} bodies, {} bindings; "
                                 "this case has {}, {}, {}, {})",
                                 s.model.dofs, s.model.elements, s.model.bodies, s.model.bindings, here.dofs,
                                 here.elements, here.bodies, here.bindings));
  const double moved = (s.reference - model.reference).cwiseAbs().maxCoeff();
  if (moved > 1e-9 * model.length_scale)
    throw InputError(file, "(file)",
                     fmt::format("the state belongs to another model: its reference configuration differs by {:.3e} m",
                                 moved));
  for (const auto& [dof, d] : s.disp)
    if (dof < 0 || dof >= here.dofs) throw InputError(file, "(file)", "a prescribed dof out of range: corrupt");
  for (const auto& [node, m] : s.moments)
    if (node < 0 || node >= model.num_nodes()) throw InputError(file, "(file)", "a moment's node out of range: corrupt");
}

}  // namespace fibra
