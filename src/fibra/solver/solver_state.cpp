#include "fibra/solver/solver_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <type_traits>

#include <zlib.h>

#include <fmt/core.h>

#include "fibra/core/error.hpp"
#include "fibra/core/file.hpp"
#include "fibra/model/model.hpp"

namespace fibra {
namespace {

// Layout (little-endian, as the machine writes it): the magic line, a version, then (from
// version 3) the kind of file and its length in bytes, the fields in the order below, the end
// mark, and (from version 3) the CRC-32 of every byte before it. A truncated file is shorter
// than its length, a damaged one fails its checksum.
constexpr char kMagic[] = "fibra state\n";
constexpr std::uint32_t kVersion = 7;  // 2: test_drag; 3: kind, length, checksum, checkpoints; 4: settling_residual;
                                       // 5: project_hessians; 6: indefinite_iterations; 7: the factor's marked contacts
constexpr char kEnd[] = "end of state\n";
constexpr std::size_t kMagicSize = sizeof(kMagic) - 1;
constexpr std::size_t kEndSize = sizeof(kEnd) - 1;
constexpr std::size_t kLengthAt = kMagicSize + 4 + 4;  // the length field's offset (from version 3)
enum class Kind : std::uint32_t { State = 0, Checkpoint = 1 };

std::uint32_t checksum(const char* data, std::size_t n) {
  uLong crc = crc32(0L, Z_NULL, 0);
  while (n > 0) {  // zlib's length is a uInt
    const uInt chunk = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    crc = crc32(crc, reinterpret_cast<const Bytef*>(data), chunk);
    data += chunk;
    n -= chunk;
  }
  return static_cast<std::uint32_t>(crc);
}

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
  In(const std::string& bytes, const std::string& path) : m_bytes(bytes), m_path(path) {}
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
    const std::uint64_t left = m_bytes.size() - m_at;
    if (n > left / bytes)
      bad(fmt::format("the file ends early: {} items of {} bytes announced, {} bytes left (truncated or corrupt)", n,
                      bytes, left));
    return n;
  }
  std::string text(std::uint64_t limit = 1u << 20) {
    std::string v(count(limit, 1), '\0');
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
    if (n > m_bytes.size() - m_at) bad("the file ends early (truncated: was its run stopped while writing it?)");
    if (n == 0) return;  // (an empty vector's data() may be null, which memcpy may not take)
    std::memcpy(p, m_bytes.data() + m_at, n);
    m_at += n;
  }
  std::size_t at() const { return m_at; }
  [[noreturn]] void bad(const std::string& why) const { throw InputError(m_path, "(file)", why); }

 private:
  const std::string& m_bytes;
  std::string m_path;
  std::size_t m_at = 0;
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

namespace {

void put_contacts(Out& o, const std::vector<ContactElement>& contacts) {
  o.put(static_cast<std::uint64_t>(contacts.size()));
  for (const ContactElement& c : contacts) {
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
}

std::vector<ContactElement> get_contacts(In& in, std::int64_t elements) {
  // Bytes per item as written: two particles (8 + 3 * 8), the normal, stiffness,
  // regularization, zone, two flags, offset, friction normal and two vectors.
  const std::uint64_t n = in.count(std::uint64_t{1} << 40, 2 * 32 + 24 + 16 + 4 + 2 + 16 + 48);
  std::vector<ContactElement> contacts(n);
  for (ContactElement& c : contacts) {
    c.a = get_particle(in);
    c.b = get_particle(in);
    if (c.a.element < 0 || c.a.element >= elements || c.b.element < 0 || c.b.element >= elements)
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
  return contacts;
}

void put_state(Out& o, const SolverState& s) {
  o.put(s.model.dofs);
  o.put(s.model.elements);
  o.put(s.model.bodies);
  o.put(s.model.bindings);
  o.put(s.reference);
  o.put(s.step);
  o.put(static_cast<std::int32_t>(s.steps_done));
  o.put(s.q);
  o.put(s.bodies);
  put_contacts(o, s.contacts);
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
}

SolverState get_state(In& in, std::uint32_t version) {
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
  s.contacts = get_contacts(in, s.model.elements);
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
  if (s.q.size() != s.model.dofs || s.reference.size() != s.model.dofs || s.force_end.size() != s.model.dofs)
    in.bad("its vectors do not match its number of dofs: the file is corrupt");
  return s;
}

void put_stats(Out& o, const SolverStats& t) {
  for (int v : {t.increments, t.iterations, t.cuts, t.factorizations, t.regularized_factorizations,
                t.shifted_iterations, t.line_search_trials, t.searched_solves, t.roundoff_convergences,
                t.binding_updates, t.limited_steps, t.reused_factorizations, t.krylov_iterations})
    o.put(static_cast<std::int32_t>(v));
  for (double v : {t.time_assembly, t.time_factorization, t.time_solve, t.factor_nonzeros}) o.put(v);
}

SolverStats get_stats(In& in) {
  SolverStats t;
  for (int* v : {&t.increments, &t.iterations, &t.cuts, &t.factorizations, &t.regularized_factorizations,
                 &t.shifted_iterations, &t.line_search_trials, &t.searched_solves, &t.roundoff_convergences,
                 &t.binding_updates, &t.limited_steps, &t.reused_factorizations, &t.krylov_iterations})
    *v = in.get<std::int32_t>();
  for (double* v : {&t.time_assembly, &t.time_factorization, &t.time_solve, &t.factor_nonzeros}) *v = in.get<double>();
  return t;
}

void put_progress(Out& o, const SolverProgress& p) {
  o.put(static_cast<std::int32_t>(p.step));
  o.put(static_cast<std::int32_t>(p.total));
  o.put(p.wall_time);
  o.put(p.lambda);
  o.put(p.dl);
  o.put(p.last_dl);
  o.put(p.last_motion);
  for (int v : {p.done, p.attempts, p.level_failures}) o.put(static_cast<std::int32_t>(v));
  for (bool v : {p.level_settled, p.relaxed, p.uncuttable}) o.put(static_cast<std::uint8_t>(v));
  o.put(p.failed_floor);
  o.put(p.failed_first);
  o.put(p.failed_dl);
  o.put(p.failed_state);
  o.put(p.failed_refusal);
  o.put(p.force_start);
  for (double v : {p.relax_drag, p.weave_depth, p.relax_residual, p.load_residual, p.last_shift, p.reference_force})
    o.put(v);
  for (bool v : {p.normals_settled, p.relax_settling, p.reuse_factor}) o.put(static_cast<std::uint8_t>(v));
  for (int v : {p.krylov_budget, p.cg_excess, p.fresh_cg, p.iteration_factor}) o.put(static_cast<std::int32_t>(v));
  put_stats(o, p.stats);
  o.put(static_cast<std::uint64_t>(p.detection_memory.size()));
  for (const std::vector<std::uint64_t>& keys : p.detection_memory) {
    o.put(static_cast<std::uint64_t>(keys.size()));
    o.bytes(keys.data(), keys.size() * sizeof(std::uint64_t));
  }
  o.put(p.settling_residual);
  o.put(static_cast<std::uint8_t>(p.project_hessians));
  o.put(static_cast<std::int32_t>(p.stats.indefinite_iterations));
  const FactorSource& f = p.factor;
  // A record without the drag on the positions (a release's, never reused) is not kept: the
  // format has no position weight, and the resumed run factorizes afresh.
  const bool valid = f.valid && f.drag.position_weight == 1.0;
  o.put(static_cast<std::uint8_t>(valid));
  if (!valid) return;
  o.put(f.q);
  o.put(f.bodies);
  put_contacts(o, f.contacts);
  o.put(f.friction.mu);
  o.put(f.friction.elastic_slip);
  o.put(f.drag.stiffness);
  o.put(f.drag.director_weight);
  o.put(f.drag.axial_weight);
  o.put(f.drag.anchor);
  o.put(static_cast<std::uint64_t>(f.moments.size()));
  for (const NodalMoment& m : f.moments) {
    o.put(static_cast<std::int64_t>(m.node));
    o.put(m.moment);
  }
  o.put(static_cast<std::uint64_t>(f.fixed.size()));
  o.bytes(f.fixed.data(), f.fixed.size());
  o.put(f.shift);
  o.put(static_cast<std::uint64_t>(f.marked.size()));
  o.bytes(f.marked.data(), f.marked.size());
}

SolverProgress get_progress(In& in, const ModelFingerprint& model, Index nodes, std::uint32_t version) {
  const std::uint64_t dofs = static_cast<std::uint64_t>(std::max<std::int64_t>(model.dofs, 0));
  auto flag = [&in]() { return in.get<std::uint8_t>() != 0; };
  // A vector of the model's dofs, or none.
  auto dof_vector = [&](const char* what) {
    VecX v = in.vecx(dofs);
    if (v.size() != 0 && v.size() != model.dofs)
      in.bad(fmt::format("its {} does not match its number of dofs: the file is corrupt", what));
    return v;
  };
  SolverProgress p;
  p.step = in.get<std::int32_t>();
  p.total = in.get<std::int32_t>();
  p.wall_time = in.get<double>();
  p.lambda = in.get<double>();
  p.dl = in.get<double>();
  p.last_dl = in.get<double>();
  p.last_motion = dof_vector("last motion");
  for (int* v : {&p.done, &p.attempts, &p.level_failures}) *v = in.get<std::int32_t>();
  for (bool* v : {&p.level_settled, &p.relaxed, &p.uncuttable}) *v = flag();
  p.failed_floor = in.get<double>();
  p.failed_first = in.get<double>();
  p.failed_dl = in.get<double>();
  p.failed_state = dof_vector("failed state");
  p.failed_refusal = in.text();
  p.force_start = dof_vector("step's start loads");
  for (double* v : {&p.relax_drag, &p.weave_depth, &p.relax_residual, &p.load_residual, &p.last_shift,
                    &p.reference_force})
    *v = in.get<double>();
  for (bool* v : {&p.normals_settled, &p.relax_settling, &p.reuse_factor}) *v = flag();
  for (int* v : {&p.krylov_budget, &p.cg_excess, &p.fresh_cg, &p.iteration_factor}) *v = in.get<std::int32_t>();
  p.stats = get_stats(in);
  p.detection_memory.resize(in.count(dofs, 8));
  for (std::vector<std::uint64_t>& keys : p.detection_memory) {
    keys.resize(in.count(std::uint64_t{1} << 32, 8));
    in.read(keys.data(), keys.size() * sizeof(std::uint64_t));
  }
  if (version >= 4) p.settling_residual = in.get<double>();
  if (version >= 5) p.project_hessians = flag();
  if (version >= 6) p.stats.indefinite_iterations = in.get<std::int32_t>();
  if (p.step < 0 || p.total < 0 || p.done < 0 || p.attempts < 0 || !(p.lambda >= 0.0 && p.lambda <= 1.0) ||
      !(p.dl >= 0.0 && p.dl <= 1.0) || p.force_start.size() != model.dofs || p.iteration_factor < 1 ||
      p.iteration_factor > 4 || !(p.last_dl >= 0.0 && p.last_dl <= 1.0) ||
      (p.last_dl > 0.0 && p.last_motion.size() != model.dofs) || !std::isfinite(p.relax_drag) || p.relax_drag < 0.0 ||
      !(p.settling_residual >= 0.0) || p.stats.indefinite_iterations < 0)
    in.bad("its progress within the step is out of range: the file is corrupt");
  FactorSource& f = p.factor;
  f.valid = flag();
  if (!f.valid) return p;
  f.q = dof_vector("factorization's state");
  f.bodies = in.doubles(std::uint64_t{1} << 40);
  f.contacts = get_contacts(in, model.elements);
  f.friction.mu = in.get<double>();
  f.friction.elastic_slip = in.get<double>();
  f.drag.stiffness = in.get<double>();
  f.drag.director_weight = in.get<double>();
  f.drag.axial_weight = in.get<double>();
  f.drag.anchor = dof_vector("factorization's drag anchor");
  const std::uint64_t moments = in.count(dofs, 8 + 24);
  for (std::uint64_t k = 0; k < moments; ++k) {
    NodalMoment m;
    m.node = in.get<std::int64_t>();
    m.moment = in.vec3();
    if (m.node < 0 || m.node >= nodes) in.bad("a moment's node out of range: the file is corrupt");
    f.moments.push_back(m);
  }
  f.fixed.resize(in.count(dofs, 1));
  in.read(f.fixed.data(), f.fixed.size());
  f.shift = in.get<double>();
  if (version >= 7) {
    f.marked.resize(in.count(f.contacts.size(), 1));
    in.read(f.marked.data(), f.marked.size());
    if (!f.marked.empty() && f.marked.size() != f.contacts.size())
      in.bad("its factorization's marked contacts do not match its contacts: the file is corrupt");
  }
  if (f.q.size() != model.dofs || f.fixed.size() != dofs || !std::isfinite(f.shift) || f.shift < 0.0 ||
      !(f.drag.stiffness >= 0.0 && std::isfinite(f.drag.stiffness)) ||
      (f.drag.stiffness > 0.0 && f.drag.anchor.size() != model.dofs))
    in.bad("its factorization's record does not match its model: the file is corrupt");
  return p;
}

// The whole file: magic, version, kind, length, the fields `body` appends, end mark, CRC.
template <class Body>
std::string envelope(Kind kind, Body&& body) {
  std::string buffer;
  Out o(buffer);
  o.bytes(kMagic, kMagicSize);
  o.put(kVersion);
  o.put(static_cast<std::uint32_t>(kind));
  o.put(std::uint64_t{0});  // the length, set below
  body(o);
  o.bytes(kEnd, kEndSize);
  o.put(std::uint32_t{0});  // the checksum, set below
  seal_state_bytes(buffer);
  return buffer;
}

std::string read_bytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path, "(file)", "cannot open the state file");
  std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) throw InputError(path, "(file)", "cannot read the state file");
  return bytes;
}

// Checks the magic line, the version and (from version 3) the length and checksum; returns the
// version and the kind of file, `in` past the header.
std::pair<std::uint32_t, Kind> open_file(In& in, const std::string& bytes) {
  char magic[kMagicSize];
  if (bytes.size() < kMagicSize) in.bad("not a fibra state file (state/STEP.bin or state/checkpoint.bin expected)");
  in.read(magic, kMagicSize);
  if (std::memcmp(magic, kMagic, kMagicSize) != 0)
    in.bad("not a fibra state file (state/STEP.bin or state/checkpoint.bin expected)");
  const auto version = in.get<std::uint32_t>();
  if (version < 1 || version > kVersion)
    in.bad(fmt::format("state file version {}, this fibra reads versions 1 to {}: run the case again", version,
                       kVersion));
  if (version < 3) return {version, Kind::State};
  const auto kind = in.get<std::uint32_t>();
  const auto length = in.get<std::uint64_t>();
  if (bytes.size() < length)
    in.bad(fmt::format("the file ends early: {} of its {} bytes (truncated: was its run stopped while writing it?)",
                       bytes.size(), length));
  if (bytes.size() > length)
    in.bad(fmt::format("{} bytes where its header says {}: the file is corrupt", bytes.size(), length));
  std::uint32_t stored = 0;
  std::memcpy(&stored, bytes.data() + bytes.size() - 4, 4);
  if (length < kLengthAt + 8 + kEndSize + 4 || checksum(bytes.data(), bytes.size() - 4) != stored)
    in.bad("its checksum does not match its contents: the file is damaged");
  if (kind > 1) in.bad(fmt::format("an unknown kind of state file ({}): the file is corrupt", kind));
  return {version, static_cast<Kind>(kind)};
}

void close_file(In& in, const std::string& bytes, std::uint32_t version) {
  char end[kEndSize];
  in.read(end, kEndSize);
  if (std::memcmp(end, kEnd, kEndSize) != 0) in.bad("no end mark: the file is corrupt");
  if (version >= 3 && in.at() + 4 != bytes.size()) in.bad("bytes after its end mark: the file is corrupt");
}

}  // namespace

void seal_state_bytes(std::string& bytes) {
  if (bytes.size() < kLengthAt + 8 + 4) return;
  const std::uint64_t length = bytes.size();
  std::memcpy(bytes.data() + kLengthAt, &length, 8);
  const std::uint32_t crc = checksum(bytes.data(), bytes.size() - 4);
  std::memcpy(bytes.data() + bytes.size() - 4, &crc, 4);
}

void write_state_file(const std::string& path, const SolverState& s) {
  write_file_atomic(path, envelope(Kind::State, [&](Out& o) { put_state(o, s); }));
}

SolverState read_state_file(const std::string& path) {
  const std::string bytes = read_bytes(path);
  In in(bytes, path);
  const auto [version, kind] = open_file(in, bytes);
  if (kind != Kind::State)
    in.bad("a checkpoint, not a step's state: a run goes on from its checkpoint with `fibra run CASE --out DIR "
           "--resume`, and from a step's state (state/STEP.bin) with [start]");
  SolverState s = get_state(in, version);
  close_file(in, bytes, version);
  return s;
}

void write_checkpoint_file(const std::string& path, const Checkpoint& c) {
  write_file_atomic(path, envelope(Kind::Checkpoint, [&](Out& o) {
                      put_state(o, c.state);
                      put_progress(o, c.progress);
                      o.put(c.run);
                      o.put(c.case_text);
                      o.put(c.case_file);
                    }));
}

Checkpoint read_checkpoint_file(const std::string& path) {
  const std::string bytes = read_bytes(path);
  In in(bytes, path);
  const auto [version, kind] = open_file(in, bytes);
  if (kind != Kind::Checkpoint)
    in.bad("a step's state, not a checkpoint: `--resume` goes on from state/checkpoint.bin");
  Checkpoint c;
  c.state = get_state(in, version);
  // The file's counts as read (a corrupt file's may be anything): the bodies clamped to what its
  // dofs can hold, so that 6 x bodies cannot overflow.
  const std::int64_t dofs = std::max<std::int64_t>(c.state.model.dofs, 0);
  const std::int64_t bodies = std::clamp<std::int64_t>(c.state.model.bodies, 0, dofs / 6);
  const Index nodes = static_cast<Index>((dofs - 6 * bodies) / 9);
  c.progress = get_progress(in, c.state.model, nodes, version);
  c.run = in.text(std::uint64_t{1} << 32);
  c.case_text = in.text(std::uint64_t{1} << 32);
  c.case_file = in.text();
  close_file(in, bytes, version);
  return c;
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
