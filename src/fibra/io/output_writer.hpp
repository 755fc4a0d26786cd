#pragma once
/// Run output: history.csv (one row per converged increment), nodes.csv, ParaView
/// collections of tube surfaces and centroid lines (fibers.pvd / lines.pvd with one .vtu per
/// written increment in the subfolders fibers/ and lines/), of contact elements (contacts.pvd,
/// contacts/) and of rigid bodies (bodies.pvd, bodies/), and summary.json. Every write is
/// checked; files that are rewritten (pvd, nodes.csv, summary.json) are replaced atomically.
/// File formats: docs/outputs.md.
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "fibra/core/types.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// One converged increment, for history.csv.
struct HistoryRow {
  std::string step;          ///< step name
  int step_index = 0;        ///< 0-based index of the step
  int increment = 0;         ///< converged increment counter within the step
  double load_factor = 0;    ///< load factor within the step, in (0, 1]
  int iterations = 0;        ///< Newton iterations of this increment
  double residual = 0;       ///< final (relative) residual norm
  double wall_time = 0;      ///< wall-clock time since the start of the run [s]
  std::vector<double> extra; ///< values of the extra columns, in the writer's order
};

/// A contact element for the ParaView output.
struct ContactPoint {
  Vec3 position = Vec3::Zero();  ///< midpoint of the two particles [m]
  Vec3 normal = Vec3::Zero();    ///< contact normal
  Vec3 friction = Vec3::Zero();  ///< tangential force [N]
  double gap = 0;                ///< [m], negative = penetration
  double normal_force = 0;       ///< [N]
  bool slip = false;             ///< on the Coulomb cone
  int zone = 0;                  ///< proximity zone
};

/// A rigid body for the ParaView output and history.
struct BodyPoint {
  std::string name;
  Vec3 center = Vec3::Zero();      ///< current centre [m]
  Mat3 frame = Mat3::Identity();   ///< columns D1, D2, D3
  Vec3 displacement = Vec3::Zero();///< centre displacement from the initial position [m]
  Vec3 rotation = Vec3::Zero();    ///< accumulated rotation components [rad]
  Vec3 force = Vec3::Zero();       ///< force the body applies to its members [N]
  Vec3 moment = Vec3::Zero();      ///< moment about its centre [N m]
  std::vector<Vec3> members;       ///< current positions of its bound members (nodes or body centres)
};

/// Creates the output directory `dir` and checks that it and those of its subfolders `subdirs`
/// (relative to it) that exist take a new file; a missing subfolder is left to be made when it
/// is first written into. Throws InputError naming the path when one is a file, cannot be
/// created or cannot be written into, so that a run stops before it starts.
void prepare_output_dir(const std::string& dir, const std::vector<std::string>& subdirs);

/// Writes all output files of a run into one directory.
class OutputWriter {
 public:
  /// Creates `dir` (and parents) and checks it and its subfolders fibers/ and lines/
  /// (prepare_output_dir: InputError when one cannot be written), opens history.csv with header: step,step_index,increment,load_factor,iterations,residual,wall_time, then the `extra_columns` names (e.g. reaction:beam:first:x).
  OutputWriter(std::string dir, const Model& model, std::vector<std::string> extra_columns, int tube_sides);
  /// Goes on writing into `dir` from `resume_point` (resume_point() of the writer of a run
  /// resumed from its checkpoint): history.csv cut back to its rows then and appended to, the
  /// collections listing the files written until then, later numbered files removed. Throws
  /// InputError naming the file when history.csv is missing or shorter than it was then.
  OutputWriter(std::string dir, const Model& model, std::vector<std::string> extra_columns, int tube_sides,
               const nlohmann::json& resume_point);
  /// Where the outputs are (history.csv's length, the collections' files), for a checkpoint.
  nlohmann::json resume_point() const;
  /// Closes history.csv.
  ~OutputWriter();
  OutputWriter(const OutputWriter&) = delete;             ///< not copyable (owns a file)
  OutputWriter& operator=(const OutputWriter&) = delete;  ///< not copyable (owns a file)

  /// Appends a history row (flushed to disk at once) and, if write_vtu, writes fibers/fibers_NNNNNN.vtu and lines/lines_NNNNNN.vtu and rewrites fibers.pvd / lines.pvd (timestep = load counter `time`) so the collections are valid after every increment.
  /// With write_vtu it also writes contacts/contacts_NNNNNN.vtu and rewrites contacts.pvd when `contacts` is non-null (even if empty), and writes bodies/bodies_NNNNNN.vtu and rewrites bodies.pvd when `bodies` is non-null and non-empty (same NNNNNN as the fibers'). Each collection lists only the files actually written, by their paths relative to the output directory.
  void write_increment(const VecX& q, const HistoryRow& row, double time, bool write_vtu,
                       const std::vector<ContactPoint>* contacts = nullptr,
                       const std::vector<BodyPoint>* bodies = nullptr);
  /// Writes nodes.csv for state q (nodes_csv_text, io/nodes_csv.hpp, which read_nodes_csv reads back): columns fiber,node,x,y,z,g1x,g1y,g1z,g2x,g2y,g2z (fiber name, node index local to the fiber), full double precision.
  void write_nodes(const VecX& q) const;
  /// Writes summary.json (pretty-printed, atomically: write tmp then rename).
  void write_summary(const nlohmann::json& summary) const;
  /// The output directory.
  const std::string& dir() const { return m_dir; }
  /// Number of .vtu pairs written so far (the next file index).
  int vtu_count() const { return static_cast<int>(m_vtu_files.size()); }

 private:
  struct FileCloser {
    void operator()(std::FILE* f) const;
  };
  std::string path(const std::string& name) const;
  /// SERIES/SERIES_NNNNNN.vtu: a series' file relative to the output directory.
  static std::string series_file(const std::string& series, int index);
  /// The path of a series' file, its subfolder created when missing.
  std::string series_path(const std::string& series, int index) const;
  void write_history_row(const HistoryRow& row);
  void write_vtu(const VecX& q, int index, double time) const;
  using PvdEntries = std::vector<std::pair<double, int>>;  ///< (time, file index) of each .vtu of a collection
  void write_pvd(const std::string& name, const std::string& prefix, const PvdEntries& entries) const;
  void write_contacts(const std::vector<ContactPoint>& contacts, int index, double time) const;
  void write_bodies(const std::vector<BodyPoint>& bodies, int index, double time) const;
  void check_state(const VecX& q) const;

  std::string m_dir;
  Model m_model;
  std::vector<std::string> m_extra_columns;
  int m_tube_sides = 12;
  std::unique_ptr<std::FILE, FileCloser> m_history;
  PvdEntries m_vtu_files;      ///< (time, file index) of each written fibers/lines .vtu pair
  PvdEntries m_contact_files;  ///< (time, file index) of each written contacts .vtu
  PvdEntries m_body_files;     ///< (time, file index) of each written bodies .vtu
};

}  // namespace fibra
