// The Slurm client (meltlab/experiments/slurm.h): the Slurm commands as child processes.
#include <meltlab/experiments/slurm.h>

#include <meltlab/core/error.h>
#include <meltlab/core/process.h>

#include <fmt/format.h>

#include <fstream>
#include <set>
#include <sstream>

namespace meltlab::experiments::slurm {
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  std::size_t b = 0;
  while (b < s.size() && s[b] == ' ') ++b;
  return s.substr(b);
}

struct Output {
  int status = -1;
  std::string out, err;
};

/// Runs a Slurm command; stdout and stderr through files beside `scratch`.
Output run(const std::vector<std::string>& argv, const fs::path& scratch) {
  fs::create_directories(scratch.parent_path());
  ProcessSpec spec;
  spec.argv = argv;
  spec.stdin_file = kNullDevice;
  spec.stdout_file = scratch;
  spec.stderr_file = fs::path(scratch.string() + ".err");
  Output o;
  o.status = run_process(spec).shell_status();
  o.out = slurp(*spec.stdout_file);
  o.err = trim(slurp(*spec.stderr_file));
  std::error_code ec;
  fs::remove(*spec.stdout_file, ec);
  fs::remove(*spec.stderr_file, ec);
  return o;
}

std::string first_line(const std::string& s) {
  const std::string t = trim(s);
  return t.substr(0, t.find('\n'));
}

std::string join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

}  // namespace

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string job_of_task(const std::string& task_id) { return task_id.substr(0, task_id.find('_')); }

std::vector<std::string> sbatch_arguments(const JobRequest& r) {
  std::vector<std::string> a{"--parsable", "--job-name=" + r.name, "--output=" + r.log.string(),
                             "--error=" + r.log.string(), "--chdir=" + r.workdir.string(),
                             // the environment of this run (MELTLAB_DATA_DIR, PATH) goes with every job
                             "--export=ALL"};
  if (!r.resources.partition.empty()) a.push_back("--partition=" + r.resources.partition);
  if (!r.resources.time.empty()) a.push_back("--time=" + r.resources.time);
  if (r.resources.cpus > 0) a.push_back(fmt::format("--cpus-per-task={}", r.resources.cpus));
  if (!r.resources.mem.empty()) a.push_back("--mem=" + r.resources.mem);
  if (r.array_size > 0) a.push_back(fmt::format("--array=0-{}", r.array_size - 1));
  if (!r.after_ok.empty()) {
    a.push_back("--dependency=afterok:" + join(r.after_ok, ":"));
    a.push_back("--kill-on-invalid-dep=yes");  // a failed dependency cancels it instead of leaving it pending
  }
  if (r.exclusive) a.push_back("--exclusive");
  a.insert(a.end(), r.extra_args.begin(), r.extra_args.end());
  a.push_back(r.script.string());
  return a;
}

std::string submit(const JobRequest& r, const fs::path& scratch) {
  std::vector<std::string> argv{"sbatch"};
  for (auto& a : sbatch_arguments(r)) argv.push_back(std::move(a));
  Output o;
  try {
    o = run(argv, scratch);
  } catch (const InputError& e) {
    throw InputError(fmt::format("sbatch: {} (is Slurm installed here? docs/cluster.md)", e.what()));
  }
  // --parsable: "ID" or "ID;CLUSTER"
  const std::string id = first_line(o.out).substr(0, first_line(o.out).find(';'));
  if (o.status != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
    throw InputError(fmt::format("sbatch refused {}: {}", r.name,
                                 first_line(o.err.empty() ? o.out : o.err).empty()
                                     ? fmt::format("exit {}", o.status)
                                     : first_line(o.err.empty() ? o.out : o.err)));
  return id;
}

void cancel(const std::vector<std::string>& job_ids, const fs::path& scratch) {
  if (job_ids.empty()) return;
  std::vector<std::string> argv{"scancel"};
  argv.insert(argv.end(), job_ids.begin(), job_ids.end());
  try {
    run(argv, scratch);
  } catch (const std::exception&) {
  }
}

std::map<std::string, TaskState> parse_squeue(const std::string& text) {
  std::map<std::string, TaskState> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    line = trim(line);
    const auto a = line.find('|'), b = line.find('|', a == std::string::npos ? a : a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    TaskState t;
    t.state = line.substr(a + 1, b - a - 1);
    t.reason = line.substr(b + 1);
    t.live = true;
    out[line.substr(0, a)] = t;
  }
  return out;
}

std::map<std::string, TaskState> parse_sacct(const std::string& text) {
  std::map<std::string, TaskState> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    line = trim(line);
    std::vector<std::string> f;
    std::stringstream ls(line);
    for (std::string x; std::getline(ls, x, '|');) f.push_back(x);
    if (f.size() < 3 || f[0].empty()) continue;
    TaskState t;
    t.state = f[1].substr(0, f[1].find(' '));  // "CANCELLED by 0"
    t.exit_code = f[2];
    t.live = t.state == "PENDING" || t.state == "RUNNING" || t.state == "REQUEUED" || t.state == "SUSPENDED";
    out[f[0]] = t;
  }
  return out;
}

std::map<std::string, TaskState> parse_scontrol(const std::string& text) {
  std::map<std::string, TaskState> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::map<std::string, std::string> kv;
    std::istringstream ls(line);
    for (std::string word; ls >> word;)
      if (const auto eq = word.find('='); eq != std::string::npos) kv.emplace(word.substr(0, eq), word.substr(eq + 1));
    if (!kv.count("JobId") || !kv.count("JobState")) continue;
    const bool array = kv.count("ArrayJobId") && kv.count("ArrayTaskId");
    const std::string id = array ? kv["ArrayJobId"] + "_" + kv["ArrayTaskId"] : kv["JobId"];
    TaskState t;
    t.state = kv["JobState"];
    t.reason = kv.count("Reason") ? kv["Reason"] : "";
    t.exit_code = kv.count("ExitCode") ? kv["ExitCode"] : "";
    t.live = t.state == "PENDING" || t.state == "RUNNING" || t.state == "COMPLETING" || t.state == "CONFIGURING" ||
             t.state == "SUSPENDED" || t.state == "REQUEUED";
    out[id] = t;
  }
  return out;
}

std::map<std::string, TaskState> query(const std::vector<std::string>& job_ids, const fs::path& scratch) {
  const std::set<std::string> wanted(job_ids.begin(), job_ids.end());
  std::map<std::string, TaskState> out;
  if (wanted.empty()) return out;
  Output q;
  try {
    q = run({"squeue", "--noheader", "--array", "--me", "--format=%i|%T|%r"}, scratch);
  } catch (const InputError& e) {
    throw InputError(fmt::format("squeue: {}", e.what()));
  }
  if (q.status != 0) throw InputError(fmt::format("squeue failed (exit {}): {}", q.status, first_line(q.err)));
  std::set<std::string> queued;
  for (auto& [id, t] : parse_squeue(q.out))
    if (wanted.count(job_of_task(id))) {
      queued.insert(job_of_task(id));
      out[id] = t;
    }
  // Jobs with no task in the queue have finished (or were never seen): ask accounting first.
  std::vector<std::string> gone;
  for (const auto& j : wanted)
    if (!queued.count(j)) gone.push_back(j);
  if (gone.empty()) return out;
  std::map<std::string, TaskState> finished;
  try {
    const Output a = run({"sacct", "--noheader", "--parsable2", "--allocations", "--format=JobID,State,ExitCode",
                          "--jobs=" + join(gone, ",")},
                         scratch);
    if (a.status == 0) finished = parse_sacct(a.out);
  } catch (const InputError&) {
  }
  if (finished.empty())
    for (const auto& j : gone) {  // accounting off: the controller remembers jobs for MinJobAge
      try {
        const Output c = run({"scontrol", "show", "job", "--oneliner", j}, scratch);
        if (c.status == 0)
          for (auto& [id, t] : parse_scontrol(c.out)) finished[id] = t;
      } catch (const InputError&) {
      }
    }
  for (auto& [id, t] : finished)
    if (wanted.count(job_of_task(id)) && !out.count(id)) out[id] = t;
  return out;
}

}  // namespace meltlab::experiments::slurm
