#include "framework/study/sweep.hpp"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <unistd.h>

#include "framework/core/parallel.hpp"
#include "framework/io/files.hpp"

namespace pneumo::study {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

// All 17 digits: the journal must give back the exact double on resume.
std::string number(double v) {
  if (std::isnan(v)) return "nan";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The shortest text that reads back as the same double (0.05, not
// 0.050000000000000003): what people read in the results.
std::string shortest(double v) {
  if (std::isnan(v)) return "nan";
  char buf[40];
  const auto end = std::to_chars(buf, buf + sizeof buf, v).ptr;
  return std::string(buf, end);
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += "\"\"";
    else if (c == '\n' || c == '\r') out += ' ';
    else out += c;
  }
  return out + "\"";
}

// CSV cells of one line (quotes with "" escapes).
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  bool in_quotes = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (in_quotes) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') cell += '"', ++i;
      else if (c == '"') in_quotes = false;
      else cell += c;
    } else if (c == '"') {
      in_quotes = true;
    } else if (c == ',') {
      cells.push_back(cell);
      cell.clear();
    } else {
      cell += c;
    }
  }
  cells.push_back(cell);
  return cells;
}

std::string journal_line(const RunRecord& r, std::size_t n_metrics) {
  std::string s = std::to_string(r.index) + (r.ok ? ",ok" : ",failed");
  for (std::size_t k = 0; k < n_metrics; ++k) {
    s += ',';
    if (r.ok) s += number(r.metrics[k]);
  }
  s += ',';
  s += std::to_string(r.steps);
  s += ',';
  s += quoted(r.reason);
  s += '\n';
  return s;
}

bool parse_journal_line(const std::string& line, std::size_t n_metrics, RunRecord& r) {
  const auto cells = split_csv(line);
  if (cells.size() != n_metrics + 4) return false;
  try {
    r.index = std::stol(cells[0]);
    r.ok = cells[1] == "ok";
    if (!r.ok && cells[1] != "failed") return false;
    r.metrics.clear();
    if (r.ok)
      for (std::size_t k = 0; k < n_metrics; ++k) r.metrics.push_back(std::stod(cells[2 + k]));
    r.steps = std::stol(cells[2 + n_metrics]);
    r.reason = cells[3 + n_metrics];
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

std::uint64_t fnv1a(std::uint64_t h, const std::string& s) {
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

std::string sweep_identity(const std::string& netlist_text, const Design& d,
                           const std::vector<Metric>& metrics, bool eliminate) {
  std::uint64_t h = 14695981039346656037ull;
  h = fnv1a(h, netlist_text);
  for (const auto& p : d.parameters) h = fnv1a(fnv1a(h, "|"), p.name);
  for (const auto& s : d.samples)
    for (double v : s) h = fnv1a(fnv1a(h, ","), number(v));
  for (const auto& m : metrics) h = fnv1a(fnv1a(h, "|"), m.name);
  if (eliminate) h = fnv1a(h, "|eliminate_aliases");
  char buf[64];
  std::snprintf(buf, sizeof buf, "# pneumo sweep journal %016llx runs %zu", static_cast<unsigned long long>(h),
                d.samples.size());
  return buf;
}

std::vector<fs::path> journal_files(const std::string& output) {
  std::vector<fs::path> out;
  const fs::path target = fs::absolute(output);
  const std::string prefix = target.filename().string() + ".journal";
  std::error_code ec;
  const fs::path dir = target.parent_path();
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name == prefix || name.rfind(prefix + ".rank", 0) == 0) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Records found in the journals of an earlier, interrupted run of the same sweep.
std::vector<RunRecord> read_journals(const std::string& output, const std::string& identity, std::size_t n_metrics,
                                     long n_runs) {
  std::vector<RunRecord> out;
  std::set<long> seen;
  for (const auto& path : journal_files(output)) {
    std::string text;
    try {
      if (fs::is_symlink(path))  // pneumo makes journals itself, never as links
        throw std::invalid_argument("sweep journal " + path.string() +
                                    ": this is a symbolic link pneumo did not make; remove it or write elsewhere (-o)");
      text = read_input_file(path.string(), "sweep journal");
    } catch (const std::invalid_argument& e) {
      throw InputError(SourceLocation{path.string(), 0, 0}, "", "", e.what());
    }
    if (text.empty()) continue;
    const auto first_end = text.find('\n');
    if (first_end == std::string::npos || text.substr(0, first_end) != identity)
      throw InputError(SourceLocation{path.string(), 1, 1}, "", "",
                       "this journal belongs to a different sweep (other netlist, parameters, samples or metrics); "
                       "delete it to start afresh, or write the results elsewhere (-o)");
    std::size_t pos = first_end + 1;
    while (pos < text.size()) {
      const auto end = text.find('\n', pos);
      if (end == std::string::npos) break;  // cut short by a kill: run it again
      RunRecord r;
      if (parse_journal_line(text.substr(pos, end - pos), n_metrics, r) && r.index >= 0 && r.index < n_runs &&
          seen.insert(r.index).second)
        out.push_back(std::move(r));
      pos = end + 1;
    }
  }
  return out;
}

// Appends finished runs to this process's journal, one flushed write each.
class Journal {
 public:
  Journal(const fs::path& path, const std::string& identity) : path_(path) {
    file_ = open_journal(path.string());  // refuses a link, device or FIFO planted there
    // Drop a trailing partial line from an earlier kill before appending.
    std::string text = read_input_file(path.string(), "sweep journal");
    const auto last = text.rfind('\n');
    std::error_code ec;
    fs::resize_file(path, last == std::string::npos ? 0 : last + 1, ec);
    if (last == std::string::npos) write(identity + "\n");
  }
  ~Journal() {
    if (file_) std::fclose(file_);
  }
  Journal(const Journal&) = delete;
  Journal& operator=(const Journal&) = delete;
  void write(const std::string& line) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (std::fwrite(line.data(), 1, line.size(), file_) != line.size() || std::fflush(file_) != 0)
      throw std::runtime_error("cannot write the sweep journal '" + path_.string() + "'");
  }

 private:
  fs::path path_;
  std::FILE* file_ = nullptr;
  std::mutex mutex_;
};

class Progress {
 public:
  Progress(long total, bool enabled) : total_(total), enabled_(enabled), tty_(isatty(2)), t0_(Clock::now()) {}
  void update(long done, long failed, bool final = false) {
    if (!enabled_ || total_ <= 0) return;
    const auto now = Clock::now();
    const int decile = static_cast<int>(10 * done / total_);
    if (final && done == last_done_) return;
    if (!final) {
      if (tty_ && now - last_ < std::chrono::milliseconds(200)) return;
      if (!tty_ && decile == last_decile_) return;
    }
    last_ = now;
    last_decile_ = decile;
    last_done_ = done;
    const double s = std::chrono::duration<double>(now - t0_).count();
    const double rate = s > 0 ? done / s : 0.0;
    const int width = 30;
    const int filled = static_cast<int>(width * done / total_);
    std::string bar(filled, '#');
    bar.resize(width, '.');
    char line[200];
    std::snprintf(line, sizeof line, "[%s] %ld/%ld runs, %ld failed, %.1f runs/s, ETA %.0f s", bar.c_str(), done,
                  total_, failed, rate, rate > 0 ? (total_ - done) / rate : 0.0);
    std::cerr << (tty_ ? "\r" : "") << line << (tty_ && !final ? "" : "\n") << std::flush;
  }

 private:
  long total_;
  bool enabled_, tty_;
  Clock::time_point t0_, last_{};
  int last_decile_ = -1;
  long last_done_ = -1;
};

constexpr const char* kResultsHeader = "run,status";

void write_results(const std::string& output, const Design& d, const std::vector<Metric>& metrics,
                   const std::vector<RunRecord>& records) {
  std::ostringstream out;
  out << kResultsHeader;
  for (const auto& p : d.parameters) out << "," << p.name << " [" << p.display_unit << "]";
  for (const auto& m : metrics) out << "," << m.name << " [" << m.unit << "]";
  out << ",steps,reason\n";
  for (const auto& r : records) {
    out << r.index << (r.ok ? ",ok" : ",failed");
    for (std::size_t j = 0; j < d.parameters.size(); ++j) out << "," << shortest(d.parameters[j].shown(d.samples[r.index][j]));
    for (std::size_t k = 0; k < metrics.size(); ++k) out << "," << (r.ok ? shortest(metrics[k].display.shown(r.metrics[k])) : "");
    out << "," << r.steps << "," << quoted(r.reason) << "\n";
  }
  write_text_atomic(output, out.str());
}

}  // namespace

bool is_sweep_results_header(const std::string& first_line) { return first_line.rfind(kResultsHeader, 0) == 0; }

SweepRunner::SweepRunner(const Netlist& netlist, const Registry& registry, std::vector<StudyParameter> parameters,
                         std::vector<Metric> metrics, const AssemblyOptions& assembly)
    : netlist_(netlist), registry_(registry), parameters_(std::move(parameters)), metrics_(std::move(metrics)),
      assembly_(assembly) {
  // Integral metrics and energy audits read extra (solver-integrated) outputs.
  plan_ = prepare_metrics(netlist_, metrics_);
}

RunRecord SweepRunner::run(const Sample& sample) const {
  RunRecord rec;
  try {
    Netlist run_nl = netlist_;
    for (std::size_t j = 0; j < parameters_.size(); ++j) set_si_value(run_nl, {parameters_[j].component, parameters_[j].parameter}, sample[j]);
    Circuit circuit = elaborate(run_nl, registry_);
    const std::vector<AuditPlan> audits = prepare_audits(plan_, run_nl, circuit);
    AssemblyOptions run_assembly = assembly_;
    run_assembly.rest_heat = run_nl.simulation.steady_start;  // its settling's rows
    System system(std::move(circuit), run_assembly);
    const RunResult run = run_system(system, solver_options(run_nl.simulation));
    rec.steps = run.solver.stats.steps;
    if (!run.solver.ok) {
      rec.reason = run.solver.message;
      return rec;
    }
    rec.metrics = compute_metrics(metrics_, plan_, audits, run_nl, run);
    rec.ok = true;
  } catch (const InputError& e) {
    rec.reason = e.what();
  } catch (const std::exception& e) {
    rec.reason = e.what();
  }
  return rec;
}

RunRecord run_one(const Netlist& netlist, const Registry& registry, const std::vector<StudyParameter>& parameters,
                  const Sample& sample, const std::vector<Metric>& metrics,
                  const AssemblyOptions& assembly) {
  return SweepRunner(netlist, registry, parameters, metrics, assembly).run(sample);
}

namespace {

// The runs journalled by an earlier, interrupted sweep of the same study:
// rank 0 reads the journals and tells the others which indices are done.
std::set<long> runs_done(const std::string& output, const std::string& identity, std::size_t metrics, long n,
                         Communicator& comm, std::vector<RunRecord>& previous) {
  std::string done_list;
  if (comm.rank() == 0) {
    previous = read_journals(output, identity, metrics, n);
    for (const auto& r : previous) {
      done_list += std::to_string(r.index);
      done_list += ' ';
    }
  }
  comm.broadcast(done_list);
  std::set<long> done;
  std::istringstream ss(done_list);
  long i;
  while (ss >> i) done.insert(i);
  return done;
}

// This rank's share of the pending runs: every size-th pending index.
std::vector<long> my_pending_runs(long n, const std::set<long>& done, const Communicator& comm) {
  std::vector<long> mine;
  long pending_count = 0;
  for (long i = 0; i < n; ++i) {
    if (done.count(i)) continue;
    if (pending_count++ % comm.size() == comm.rank()) mine.push_back(i);
  }
  return mine;
}

// Runs `mine` on threads, each journalled as it finishes.
std::vector<RunRecord> run_pending(const Model& model, const Design& design,
                                   const std::vector<Metric>& metrics, const std::vector<long>& mine,
                                   const SweepOptions& opt, const fs::path& journal_path, const std::string& identity,
                                   bool show_progress) {
  std::vector<RunRecord> fresh;
  Journal journal(journal_path, identity);
  std::mutex mutex;
  long finished = 0, failed = 0;
  Progress progress(static_cast<long>(mine.size()), show_progress);
  const long todo = opt.stop_after >= 0 ? std::min<long>(opt.stop_after, mine.size()) : static_cast<long>(mine.size());
  const SweepRunner runner(model.netlist, model.registry, design.parameters, metrics, opt.assembly);
  parallel_for(todo, opt.threads, [&](int, long k) {
    RunRecord rec = runner.run(design.samples[mine[k]]);
    rec.index = mine[k];
    journal.write(journal_line(rec, metrics.size()));
    std::lock_guard<std::mutex> lock(mutex);
    failed += rec.ok ? 0 : 1;
    progress.update(++finished, failed);
    fresh.push_back(std::move(rec));
  });
  progress.update(finished, failed, true);
  return fresh;
}

// Rank 0: every rank's records as journal lines, with the earlier ones;
// when all runs are there, the results file is written and the journals go.
void collect_results(const std::vector<std::string>& gathered, std::vector<RunRecord> all, const std::string& output,
                     const Design& design, const std::vector<Metric>& metrics, const SweepOptions& opt,
                     SweepSummary& summary) {
  const long n = static_cast<long>(design.samples.size());
  bool complete = true;
  for (const auto& g : gathered) {
    std::istringstream ss(g);
    std::string line;
    std::getline(ss, line);
    complete &= line == "complete";
    while (std::getline(ss, line)) {
      RunRecord r;
      if (parse_journal_line(line, metrics.size(), r)) all.push_back(std::move(r));
    }
  }
  std::sort(all.begin(), all.end(), [](const RunRecord& a, const RunRecord& b) { return a.index < b.index; });
  all.erase(std::unique(all.begin(), all.end(), [](const RunRecord& a, const RunRecord& b) { return a.index == b.index; }),
            all.end());
  complete &= static_cast<long>(all.size()) == n;
  summary.complete = complete;
  for (const auto& r : all) summary.failed += r.ok ? 0 : 1;
  if (!complete) return;
  write_results(output, design, metrics, all);
  if (!opt.keep_journal) {
    std::error_code ec;
    for (const auto& p : journal_files(output)) fs::remove(p, ec);
  }
  summary.records = std::move(all);
}

}  // namespace

SweepSummary run_sweep(const Model& model, const Design& design, const std::string& output,
                       const SweepOptions& opt, Communicator& comm) {
  const auto t0 = Clock::now();
  try {
    check_output_file(output, "-o", {model.path});
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{"-o", 0, 0}, "", "", e.what());
  }
  const auto metrics = select_metrics(model.netlist, model.registry, opt.metrics);
  const long n = static_cast<long>(design.samples.size());
  const std::string identity = sweep_identity(model.identity(), design, metrics, opt.assembly.eliminate_aliases);
  if (const auto parent = fs::path(output).parent_path(); !parent.empty()) fs::create_directories(parent);

  std::vector<RunRecord> previous;
  const std::set<long> done = runs_done(output, identity, metrics.size(), n, comm, previous);
  const std::vector<long> mine = my_pending_runs(n, done, comm);
  SweepSummary summary;
  summary.runs = n;
  summary.ranks = comm.size();
  summary.done_before = static_cast<long>(done.size());
  const fs::path journal_path =
      comm.size() > 1 ? fs::path(output + ".journal.rank" + std::to_string(comm.rank())) : fs::path(output + ".journal");
  const std::vector<RunRecord> fresh = run_pending(model, design, metrics, mine, opt, journal_path,
                                                   identity, opt.progress && comm.rank() == 0);
  summary.computed = static_cast<long>(fresh.size());
  const bool my_part_complete = summary.computed == static_cast<long>(mine.size());

  std::string lines = my_part_complete ? "complete\n" : "incomplete\n";
  for (const auto& r : fresh) lines += journal_line(r, metrics.size());
  const auto gathered = comm.gather(lines);
  if (comm.rank() == 0) collect_results(gathered, std::move(previous), output, design, metrics, opt, summary);
  comm.barrier();
  summary.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return summary;
}

std::string failure_summary(const std::vector<RunRecord>& records, std::size_t shown) {
  std::map<std::string, long> count;
  for (const auto& r : records)
    if (!r.ok) ++count[r.reason.empty() ? "no reason recorded" : r.reason];
  std::vector<std::pair<long, std::string>> by_count;
  for (const auto& [reason, n] : count) by_count.push_back({-n, reason});
  std::sort(by_count.begin(), by_count.end());
  std::string s;
  for (std::size_t i = 0; i < by_count.size() && i < shown; ++i)
    s += "  " + std::to_string(-by_count[i].first) + (by_count[i].first == -1 ? " run: " : " runs: ") +
         by_count[i].second + "\n";
  if (by_count.size() > shown) s += "  (" + std::to_string(by_count.size() - shown) + " other reasons)\n";
  return s;
}

SweepTable read_sweep_csv(const std::string& path) {
  check_input_file(path, "sweep results");
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open '" + path + "'");
  SweepTable t;
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(path + ": empty");
  t.columns = split_csv(line);
  while (std::getline(in, line))
    if (!line.empty()) t.rows.push_back(split_csv(line));
  return t;
}

}  // namespace pneumo::study
