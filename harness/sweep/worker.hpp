#pragma once
// Sweep runs in a worker process (the default; `caustics sweep --isolate-runs` starts one process per
// run instead). Starting a process per run costs more than most renders: the program starts, loads the
// scene, builds the frame (tracer, receiver chart, camera G-buffer) and reads the cached reference, about
// a second, while a render takes milliseconds. A worker, `caustics sweep-worker`, is one such process that
// renders the runs it is sent one after another, keeping the scene frame and reference of the current
// (scene, frame, reference settings) loaded between them (run/render_run.hpp, LoadedFrame).
//
// Protocol, one JSON line each way over a socket that is the worker's stdin and stdout:
//   request  {"argv": ["render", SCENE, "--method", ...], "log": "DIR/runs/ID/log.txt"}
//   reply    {"exit": 0 | 1 | 2}
// argv is exactly what a per-run child gets after the program name, and is parsed by the same `render`
// command; during the run the worker's stdout and stderr are the run's log file, so logs (and the last
// line the sweep quotes from them) read as in a per-run child; the exit status is what that child's would
// be (0 ok, 2 bad input: the run is skipped, 1 any other error).
//
// Still isolated: each run's method is created afresh and its thread limit set as in a child; the parent
// waits for each reply no longer than the run's time limit. A worker that outlives it is killed with its
// process group, and one that dies is reaped: the parent sees EOF on the socket or, at least once a
// second, the worker's ended status (a process the worker started may hold the socket open). Either way
// that run is recorded as a per-run child's would be (ChildResult: timed out, crashed with its signal, or
// its exit code; a worker that exited without answering also leaves a line in the run's log), and the
// next run starts a new worker, as does a run after a worker that died between runs. The worker dies
// with the sweep (PR_SET_PDEATHSIG).
#include <sys/types.h>

#include <functional>
#include <string>
#include <vector>

namespace caustics {

// How a run's process ended (a per-run child, or a worker's answer for one run).
struct ChildResult {
    int exit_code = -1;
    int signal = 0;
    bool timed_out = false;
};

// Runs argv (a per-run child, `--isolate-runs`) with stdout and stderr to log_path. The child is killed
// if this process dies (so an interrupted sweep leaves no run writing behind its back) or when it
// outlives timeout_s (<= 0: no limit).
ChildResult run_child(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s);

// The parent's side: one worker at a time, started on the first run and again after one was lost.
class SweepWorker {
public:
    explicit SweepWorker(std::string program);   // the `caustics` executable
    ~SweepWorker();                              // ends the worker: EOF on its stdin, then reaped
    SweepWorker(const SweepWorker&) = delete;
    SweepWorker& operator=(const SweepWorker&) = delete;

    // Runs `caustics ARGV...` in the worker with stdout and stderr to log_path; timeout_s <= 0: no limit.
    ChildResult run(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s);

private:
    void start();
    void stop(bool kill_group, int* status);

    std::string program_;
    pid_t pid_ = -1;
    int socket_ = -1;
    std::string pending_;   // bytes read past the last reply line
};

// The worker's side (`caustics sweep-worker`): serves requests from stdin until EOF; `render` runs one
// argv in-process and returns its exit status (it reports its own errors on stderr). Returns 0 at EOF,
// 1 for a request it cannot read.
int serve_sweep_worker(const std::function<int(const std::vector<std::string>& argv)>& render);

}  // namespace caustics
