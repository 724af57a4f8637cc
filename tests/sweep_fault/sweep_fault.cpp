// sweep_fault: a method plugin that fails on request, for the sweep's isolation tests
// (tests/test_sweep_worker.cpp). With fault=none it renders nothing and is ok; with segv it dies of
// SIGSEGV, with abort of SIGABRT, with hang it never returns: what a broken method does to the process
// that runs it, in a per-run child or in a sweep worker alike. fork_segv first starts a process that
// outlives it by 8 s and holds every descriptor it had (in a worker: the socket to the sweep), then dies
// of SIGSEGV: the sweep must see the death without waiting for EOF. The fault strikes inside render(), in
// the timed region, after the scene, the frame and the method's preparation have succeeded.
// work_ms > 0 makes render() busy-wait that long (times SWEEP_FAULT_SLOWDOWN, default 1, read once from the
// environment): a known cost, and a build with an injected slowdown, for `caustics compare`'s tests.
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <memory>
#include <thread>

#include <unistd.h>

#include <stdexcept>

#include <caustics/api/method.hpp>
#include <caustics/api/registry.hpp>

namespace sweep_fault {
namespace {

using namespace caustics;

class SweepFault final : public Method {
public:
    SweepFault(std::string fault, double work_ms) : fault_(std::move(fault)), work_ms_(work_ms) {
        if (const char* f = std::getenv("SWEEP_FAULT_SLOWDOWN")) work_ms_ *= std::atof(f);
        if (fault_ == "create") throw std::runtime_error("sweep_fault: asked to fail on create");
    }

    Capability capabilities(const Scene&) const override { return Capability::yes(); }

    CausticOutput render(const FrameGeometry&, const RenderRequest&) override {
        if (fault_ == "fork_segv" && fork() == 0) {
            std::this_thread::sleep_for(std::chrono::seconds(8));
            _exit(0);
        }
        if (fault_ == "segv" || fault_ == "fork_segv") std::raise(SIGSEGV);
        if (fault_ == "abort") std::abort();
        if (fault_ == "hang")
            while (true) std::this_thread::sleep_for(std::chrono::seconds(1));
        const auto start = std::chrono::steady_clock::now();
        while (std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() < work_ms_) {
        }
        return {};
    }

    AccuracyClaim accuracy_claim(const FrameGeometry&) const override {
        return AccuracyClaim::outside("draws nothing: a test of failing runs");
    }

private:
    std::string fault_;
    double work_ms_ = 0.0;
};

MethodInfo info() {
    MethodInfo m;
    m.name = "sweep_fault";
    m.doc = "Fails on request (fault=segv|abort|hang|fork_segv in render, create in its constructor), else renders "
            "nothing: the sweep's isolation tests";
    m.params = {
        {"grid", ParamType::Int, "1", 1, 1, {}, "no grid (only 1 is valid)"},
        {"iterations", ParamType::Int, "1", 1, 1, {}, "nothing iterates (only 1 is valid)"},
        {"fault", ParamType::Enum, "none", 0, 0, {"none", "segv", "abort", "hang", "fork_segv", "create"}, "how it fails"},
        {"work_ms", ParamType::Float, "0", 0, 1000, {}, "busy-wait this long per render (times SWEEP_FAULT_SLOWDOWN)"},
    };
    m.create = [](const ParamSet& p) -> std::unique_ptr<Method> {
        return std::make_unique<SweepFault>(p.get_enum("fault"), p.get_float("work_ms"));
    };
    return m;
}

}  // namespace
}  // namespace sweep_fault

CAUSTICS_REGISTER_METHOD(sweep_fault::info);
