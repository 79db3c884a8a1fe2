// mdtool._sil: the mcsim scenario runner in-process (nanobind). The same
// mcsim::prepare_run / execute_run as `mcsim run`, the trajectory kept in
// memory at full double precision instead of a CSV (which prints the same
// values with %.9g). The Python side is mdtool/sil.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <exception>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "run.hpp"
#include "scenario.hpp"

namespace nb = nanobind;

#include "mdtool_git_hash.h"  // MDTOOL_GIT_HASH, written at every build (git_hash.cmake)

namespace {

using Sets = std::vector<std::pair<std::string, std::string>>;

// Counts rows and keeps none (campaigns need only the summary).
class CountingSink : public mcsim::ColumnSink {
 public:
  using mcsim::RowSink::row;
  void row(const double* values, size_t n) override {
    if (n != names().size()) throw std::logic_error("CSV row width does not match header");
    ++rows_;
  }
};

// One run. Invalid inputs (unknown scenario, bad motor file, bad key=value,
// a duration out of range) raise UsageError before anything runs; a run that
// does not pass returns its summary (with its verdict) and trajectory with
// mcsim's message and error_kind: "usage" (a setting refused inside the run:
// mcsim's exit code 2), "failed" (the run stopped on its way: a drive fault,
// a sequence that stopped, an error; exit 1) or "verdict" (it ran to its end
// and its verdict is not a pass: exit 1).
nb::dict run(const std::string& scenario, const std::string& motor, const std::string& board,
             const Sets& sets, double duration_s, bool trajectory) {
  mcsim::PreparedRun prepared = mcsim::prepare_run(scenario, motor, board, sets, "", duration_s);
  mcsim::ColumnSink* sink = trajectory ? new mcsim::ColumnSink() : new CountingSink();
  nb::capsule owner(sink, [](void* p) noexcept { delete static_cast<mcsim::ColumnSink*>(p); });
  mcsim::Summary summary;
  mcsim::Progress progress(false);
  std::string error, kind;
  {
    nb::gil_scoped_release unlocked;
    const mcsim::RunOutcome o = mcsim::execute_run(prepared, *sink, summary, progress);
    error = o.message;
    if (o.kind == mcsim::RunOutcome::Kind::kRefused) kind = "usage";
    if (o.kind == mcsim::RunOutcome::Kind::kFailed) kind = o.stopped ? "failed" : "verdict";
  }
  const size_t ncols = sink->names().size();
  const size_t nrows = trajectory ? sink->rows() : 0;
  nb::ndarray<nb::numpy, double, nb::ndim<2>> data(const_cast<double*>(sink->data().data()),
                                                   {nrows, ncols}, owner);
  nb::dict numbers, texts, objects, out;
  for (const auto& kv : summary.numbers()) numbers[kv.first.c_str()] = kv.second;
  for (const auto& kv : summary.texts()) texts[kv.first.c_str()] = kv.second;
  for (const auto& o : summary.objects()) {  // e.g. commission's "identified": {...}
    nb::dict d;
    for (const auto& kv : o.second) d[kv.first.c_str()] = kv.second;
    objects[o.first.c_str()] = d;
  }
  out["columns"] = sink->names();
  out["rows"] = sink->rows();
  out["data"] = data;
  out["numbers"] = numbers;
  out["texts"] = texts;
  out["objects"] = objects;
  out["error"] = error.empty() ? nb::none() : nb::cast(error);
  out["error_kind"] = kind.empty() ? nb::none() : nb::cast(kind);
  return out;
}

nb::list scenarios() {
  nb::list l;
  for (const auto& s : mcsim::registry()) {
    l.append(nb::make_tuple(s.name, s.description, s.default_duration_s, bool(s.motor_params),
                            s.takes_duration));
  }
  return l;
}

// The declared parameters of a scenario (for a motor scenario, from its files).
nb::list params(const std::string& scenario, const std::string& motor, const std::string& board) {
  const mcsim::Scenario& s = mcsim::need_scenario(scenario);
  const auto files = mcsim::motor_files(s, motor, board);
  nb::list l;
  for (const auto& p : files ? s.motor_params(*files) : s.params) {
    nb::dict d;
    d["key"] = p.key;
    d["default"] = p.default_value;
    d["unit"] = p.unit;
    d["help"] = p.help;
    d["min"] = p.min_value;
    d["max"] = p.max_value;
    nb::dict ch;
    for (const auto& c : p.choices) ch[c.first.c_str()] = c.second;
    d["choices"] = ch;
    l.append(d);
  }
  return l;
}

}  // namespace

NB_MODULE(_sil, m) {
  m.doc() = "mcsim scenario runner in-process (see mdtool.sil)";
  nb::exception<mcsim::UsageError>(m, "UsageError", PyExc_ValueError);
  m.def("run", &run, nb::arg("scenario"), nb::arg("motor"), nb::arg("board"), nb::arg("sets"),
        nb::arg("duration_s"), nb::arg("trajectory") = true);
  m.def("scenarios", &scenarios);
  m.def("params", &params, nb::arg("scenario"), nb::arg("motor"), nb::arg("board"));
  m.attr("max_duration_s") = mcsim::kMaxDurationS;  // the longest run (scenario.hpp)
  m.attr("git_hash") = MDTOOL_GIT_HASH;
  m.attr("build_type") = MDTOOL_BUILD_TYPE;  // CMake's build type: Debug, Release, ...
}
