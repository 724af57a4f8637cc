#include <caustics/sweep/worker.hpp>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

namespace caustics {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

// Writes all of `text`; false when the other end is gone. MSG_NOSIGNAL: a dead worker is an answer
// (EPIPE), not a SIGPIPE that would end the sweep.
bool send_all(int fd, const std::string& text) {
    std::size_t done = 0;
    while (done < text.size()) {
        const ssize_t n = send(fd, text.data() + done, text.size() - done, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        done += static_cast<std::size_t>(n);
    }
    return true;
}

// One read of `fd` appended to `pending` (retried on EINTR); false at EOF or on an error.
bool read_more(int fd, std::string& pending) {
    char buf[4096];
    while (true) {
        const ssize_t n = read(fd, buf, sizeof buf);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        pending.append(buf, static_cast<std::size_t>(n));
        return true;
    }
}

// Moves the first complete line of `pending` (without its newline) into `line`; false if there is none.
bool take_line(std::string& pending, std::string& line) {
    const std::size_t end = pending.find('\n');
    if (end == std::string::npos) return false;
    line = pending.substr(0, end);
    pending.erase(0, end + 1);
    return true;
}

// The next line of `fd` into `line`, reading into `pending`; false at EOF.
bool read_line(int fd, std::string& pending, std::string& line) {
    while (!take_line(pending, line))
        if (!read_more(fd, pending)) return false;
    return true;
}

// fork() for a child that must not outlive this process: in the child (0 returned), optionally its own
// process group, then PR_SET_PDEATHSIG, and an exit if this process died before that took effect. Only
// async-signal-safe calls happen in the child (the caller's process may have threads); the caller's
// child branch goes on to exec.
pid_t fork_tied_child(bool own_group) {
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid == 0) {
        if (own_group) setpgid(0, 0);
        if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0) _exit(127);
        if (getppid() != parent) _exit(127);
    }
    return pid;
}

// Whether process `pid` has ended (it stays unreaped).
bool has_ended(pid_t pid) {
    siginfo_t info{};
    return waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == pid;
}

void flush_output() {
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
}

}  // namespace

ChildResult run_child(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const pid_t pid = fork_tied_child(false);
    if (pid < 0) throw std::runtime_error("sweep: fork failed");
    if (pid == 0) {
        const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            dup2(fd, STDOUT_FILENO);
            dup2(fd, STDERR_FILENO);
            close(fd);
        }
        execv(args[0], args.data());
        _exit(127);
    }
    ChildResult result;
    const auto start = Clock::now();
    int status = 0;
    while (true) {
        const pid_t r = waitpid(pid, &status, timeout_s > 0 ? WNOHANG : 0);
        if (r == pid) break;
        if (r < 0) throw std::runtime_error("sweep: waitpid failed");
        const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
        if (elapsed > timeout_s) {
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            result.timed_out = true;
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
    return result;
}


SweepWorker::SweepWorker(std::string program) : program_(std::move(program)) {}

SweepWorker::~SweepWorker() {
    if (pid_ < 0) return;
    // EOF on its stdin ends an idle worker; one that does not end within a few seconds is killed.
    shutdown(socket_, SHUT_WR);
    const auto deadline = Clock::now() + std::chrono::seconds(5);
    bool ended = false;
    while (!ended && Clock::now() < deadline) {
        ended = has_ended(pid_);
        if (!ended) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    int status = 0;
    stop(!ended, &status);
}

void SweepWorker::start() {
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) throw std::runtime_error("sweep: socketpair failed");
    // Everything the child needs is made before fork: only async-signal-safe calls happen between fork
    // and exec, as the sweep's process may have threads.
    const std::string mode = "sweep-worker";
    char* const args[] = {const_cast<char*>(program_.c_str()), const_cast<char*>(mode.c_str()), nullptr};
    // Its own process group, so that a timeout kills whatever it started too.
    const pid_t pid = fork_tied_child(true);
    if (pid < 0) {
        close(sv[0]);
        close(sv[1]);
        throw std::runtime_error("sweep: fork failed");
    }
    if (pid == 0) {
        dup2(sv[1], STDIN_FILENO);             // dup2 clears close-on-exec on the copies
        dup2(sv[1], STDOUT_FILENO);
        execv(args[0], args);
        _exit(127);
    }
    setpgid(pid, pid);   // also here, so that the group exists before any kill (fails harmlessly after exec)
    close(sv[1]);
    socket_ = sv[0];
    pid_ = pid;
    pending_.clear();
}

void SweepWorker::stop(bool kill_group, int* status) {
    if (kill_group) kill(-pid_, SIGKILL);
    // Waited for but not yet reaped, the worker keeps its process id, and so its group's id, from being
    // reused while the rest of its group (anything it started) is killed.
    siginfo_t info{};
    while (waitid(P_PID, static_cast<id_t>(pid_), &info, WEXITED | WNOWAIT) < 0 && errno == EINTR) {
    }
    kill(-pid_, SIGKILL);
    while (waitpid(pid_, status, 0) < 0 && errno == EINTR) {
    }
    close(socket_);
    socket_ = -1;
    pid_ = -1;
    pending_.clear();
}

ChildResult SweepWorker::run(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s) {
    const std::string request = json{{"argv", argv}, {"log", log_path}}.dump() + "\n";
    // A worker that died after its last answer (between runs) is replaced. Checked before sending: a
    // process it started may still hold the socket open, and then the request would go through.
    if (pid_ >= 0 && has_ended(pid_)) {
        int status = 0;
        stop(true, &status);
    }
    if (pid_ < 0) start();
    const auto started = Clock::now();
    if (!send_all(socket_, request)) {
        int status = 0;
        stop(true, &status);
        start();
        if (!send_all(socket_, request)) throw std::runtime_error("sweep: a new worker does not take requests");
    }
    ChildResult result;
    // The worker's end: its status as a per-run child's would be. A worker that exited without answering
    // (it could not read the request, or lost its descriptors) leaves a line in the run's log when the run
    // wrote none, so that the sweep quotes a reason after the exit code.
    auto ended = [&](bool timed_out) {
        int status = 0;
        stop(timed_out, &status);
        result.timed_out = timed_out;
        if (timed_out) return result;
        if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
        if (!WIFEXITED(status)) return result;
        result.exit_code = WEXITSTATUS(status);
        std::error_code ec;
        if (!std::filesystem::exists(log_path, ec) || std::filesystem::file_size(log_path, ec) == 0)
            std::ofstream(log_path, std::ios::app) << "caustics: error: the sweep worker exited (status "
                                                   << result.exit_code << ") without answering for this run\n";
        return result;
    };
    std::string line;
    while (true) {
        if (take_line(pending_, line)) {
            const json reply = json::parse(line, nullptr, false);
            if (reply.is_object() && reply.contains("exit") && reply["exit"].is_number_integer()) {
                result.exit_code = reply["exit"].get<int>();
                return result;
            }
            int status = 0;
            stop(true, &status);
            throw std::runtime_error("sweep: unreadable answer from the worker");
        }
        // Waits in slices of at most a second: EOF on the socket is not the only sign of a dead worker,
        // since a process it started and that outlived it may still hold the socket open.
        int wait_ms = 1000;
        if (timeout_s > 0.0) {
            const double left = timeout_s - std::chrono::duration<double>(Clock::now() - started).count();
            if (left <= 0.0) return ended(true);
            wait_ms = static_cast<int>(std::min(std::ceil(left * 1000.0), 1000.0));
        }
        pollfd p{socket_, POLLIN, 0};
        const int ready = poll(&p, 1, wait_ms);
        if (ready < 0 && errno != EINTR) throw std::runtime_error("sweep: poll failed");
        if (ready > 0) {
            // EOF (or a broken socket): the worker died during the run. Its status says how.
            if (!read_more(socket_, pending_)) return ended(false);
        } else if (ready == 0 && has_ended(pid_)) {
            // Dead with its socket still open elsewhere: whatever it wrote before it died is read first.
            pollfd q{socket_, POLLIN, 0};
            if (poll(&q, 1, 0) > 0 && read_more(socket_, pending_)) continue;
            return ended(false);
        }
    }
}

int serve_sweep_worker(const std::function<int(const std::vector<std::string>& argv)>& render) {
    // The requests and answers keep a descriptor of their own; stdin and stdout become /dev/null, and
    // between runs stderr is the one the worker was started with, so nothing a run leaves behind (a
    // thread still printing) can write into the answers.
    const int channel = fcntl(STDIN_FILENO, F_DUPFD_CLOEXEC, 3);
    const int idle_stderr = fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 3);
    const int null = open("/dev/null", O_RDWR | O_CLOEXEC);
    if (channel < 0 || idle_stderr < 0 || null < 0) {
        std::fprintf(stderr, "caustics: error: sweep-worker: cannot set up its descriptors\n");
        return 1;
    }
    dup2(null, STDIN_FILENO);
    dup2(null, STDOUT_FILENO);
    std::string pending, line;
    while (read_line(channel, pending, line)) {
        const json request = json::parse(line, nullptr, false);
        std::vector<std::string> argv;
        std::string log;
        try {
            argv = request.at("argv").get<std::vector<std::string>>();
            log = request.at("log").get<std::string>();
        } catch (const std::exception&) {
            std::fprintf(stderr, "caustics: error: sweep-worker: unreadable request: %s\n", line.substr(0, 200).c_str());
            return 1;
        }
        flush_output();
        const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd >= 0) {
            dup2(fd, STDOUT_FILENO);
            dup2(fd, STDERR_FILENO);
            close(fd);
        }
        int code = 1;
        try {
            code = render(argv);
        } catch (const std::exception& e) {
            std::cerr << "caustics: error: internal failure: " << e.what() << "\n";
        } catch (...) {
            std::cerr << "caustics: error: internal failure: unknown exception\n";
        }
        flush_output();
        dup2(null, STDOUT_FILENO);
        dup2(idle_stderr, STDERR_FILENO);
        if (!send_all(channel, json{{"exit", code}}.dump() + "\n")) return 1;
    }
    return 0;
}

}  // namespace caustics
