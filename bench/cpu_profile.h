// A sampling CPU profiler for the benchmarks, for machines with no perf
// (the lent GPU machine has neither perf nor gdb). While started, each
// thread that exists at start() has a POSIX timer on its own CPU clock,
// set to 1 ms and sent to that thread as SIGPROF: a process-wide
// ITIMER_PROF would interrupt whichever thread takes the signal, often one
// asleep, since Mesa's and drivers' threads block signals. The kernel
// checks these timers once per scheduler tick (4 ms at HZ=250), so a
// signal stands for 1 + si_overrun expiries and is weighted so. The handler
// stores the thread's call stack (backtrace()) in a fixed buffer; report()
// names the frames with dladdr. Threads that block SIGPROF or start after
// start() (parallel_for's, native/src/parallel.h) are not sampled: their
// time shows in process_cpu_ms() but not in the shares. backtrace() is not
// async-signal-safe (a sample inside the unwinder or the loader could
// deadlock); the first call loads libgcc before any signal, and this is a
// benchmark's tool, not the engine's.
//
// Two views, each the share of the CPU time sampled:
//  - where the time is spent: the innermost frame (library: function);
//  - which engine function spent it, itself or in the calls it made into
//    the driver or libc: the innermost frame inside the benchmark binary.
// A frame time that the engine's GPU timestamps show as stage time while
// the GPU should be idle is CPU time spent issuing it: this says where.
// The benchmarks link with ENABLE_EXPORTS (-rdynamic), so the engine's
// functions have names; a driver's code shows as its library and nearest
// exported symbol.
//
//   CpuProfile p; p.start(); ...; p.stop(); p.report("title", stdout);
#pragma once

#include <cxxabi.h>
#include <dirent.h>
#include <dlfcn.h>
#include <execinfo.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace deferred::bench {

// DEFERRED_BENCH_PROFILE set and not "0" or empty.
inline bool profile_requested() {
    const char* v = std::getenv("DEFERRED_BENCH_PROFILE");
    return v && *v && std::strcmp(v, "0") != 0;
}

// User + system time of every thread of the process so far (ms).
inline double process_cpu_ms() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) * 1e3 + double(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-3;
}

class CpuProfile {
public:
    static constexpr int kDepth = 48;
    static constexpr std::size_t kMaxSamples = 1 << 16;

    CpuProfile() : frames_(kMaxSamples * kDepth), depths_(kMaxSamples), weights_(kMaxSamples) {}
    ~CpuProfile() { stop(); }

    // Only one profile runs at a time (one SIGPROF handler per process).
    void start() {
        void* warm[4];
        backtrace(warm, 4);  // loads libgcc's unwinder outside the handler
        active() = this;
        count_.store(0);
        threads_ = 0;
        struct sigaction sa {};
        sa.sa_sigaction = &CpuProfile::on_signal;
        sa.sa_flags = SA_RESTART | SA_SIGINFO;
        sigemptyset(&sa.sa_mask);
        sigaction(SIGPROF, &sa, &previous_);
        // One timer per thread, on the thread's CPU clock (Linux's clock id
        // of thread tid: (~tid << 3) | CPUCLOCK_PERTHREAD | CPUCLOCK_SCHED).
        if (DIR* d = opendir("/proc/self/task")) {
            while (dirent* e = readdir(d)) {
                const int tid = std::atoi(e->d_name);
                if (tid <= 0) continue;
                sigevent ev{};
                ev.sigev_notify = SIGEV_THREAD_ID;
                ev.sigev_signo = SIGPROF;
                ev._sigev_un._tid = tid;
                const clockid_t clock = clockid_t((~unsigned(tid) << 3) | 6u);
                timer_t timer;
                if (timer_create(clock, &ev, &timer) != 0) continue;
                itimerspec t{};
                t.it_interval.tv_nsec = 1000000;
                t.it_value.tv_nsec = 1000000;
                timer_settime(timer, 0, &t, nullptr);
                timers_.push_back(timer);
                ++threads_;
            }
            closedir(d);
        }
        running_ = true;
    }

    void stop() {
        if (!running_) return;
        for (timer_t t : timers_) timer_delete(t);
        timers_.clear();
        sigaction(SIGPROF, &previous_, nullptr);
        active() = nullptr;
        running_ = false;
    }

    // report() into a string (the benchmarks print their profiles after
    // their tables).
    std::string report_string(const char* title) const {
        char* buf = nullptr;
        std::size_t len = 0;
        std::FILE* mem = open_memstream(&buf, &len);
        if (!mem) return std::string("\nCPU profile: ") + title + ": no memory stream\n";
        report(title, mem);
        std::fclose(mem);
        std::string s(buf, len);
        std::free(buf);
        return s;
    }

    // After stop().
    void report(const char* title, std::FILE* out, std::size_t rows = 20) const {
        const std::size_t n = std::min(count_.load(), kMaxSamples);
        std::size_t total = 0;  // ms of CPU time the samples stand for
        for (std::size_t s = 0; s < n; ++s) total += weights_[s];
        std::fprintf(out,
                     "\nCPU profile: %s (%zu samples standing for %zu ms of CPU time, over the %zu threads that "
                     "existed at its start)\n\n",
                     title, n, total, threads_);
        if (n == 0) return;
        Dl self_base;
        dladdr(reinterpret_cast<void*>(&CpuProfile::on_signal), &self_base.info);
        std::map<std::string, std::size_t> innermost, engine, pairs;
        for (std::size_t s = 0; s < n; ++s) {
            void* const* f = &frames_[s * kDepth];
            const int d = depths_[s];
            // Frames 0-1 are this handler and the kernel's signal trampoline.
            int first = 0;
            for (int i = 0; i < d; ++i) {
                Dl dl;
                if (dladdr(f[i], &dl.info) && dl.info.dli_sname && std::strstr(dl.info.dli_sname, "on_signal")) {
                    first = i + 2;
                    break;
                }
            }
            if (first == 0 || first >= d) continue;  // the handler's frame not found
            const std::size_t w = weights_[s];
            const std::string where = name(f[first]);
            innermost[where] += w;
            std::string caller = "(no engine frame)";
            for (int i = first; i < d; ++i) {
                Dl dl;
                if (dladdr(f[i], &dl.info) && dl.info.dli_fbase == self_base.info.dli_fbase) {
                    caller = symbol(dl, f[i]);
                    break;
                }
            }
            engine[caller] += w;
            pairs[caller + "  ->  " + library(f[first])] += w;
        }
        print_top(out, "innermost frame (library: function)", innermost, total, rows);
        print_top(out, "engine function (itself and what it called)", engine, total, rows);
        print_top(out, "engine function -> library it was in", pairs, total, rows);
    }

private:
    struct Dl {
        Dl_info info{};
    };

    static CpuProfile*& active() {
        static CpuProfile* p = nullptr;
        return p;
    }

    static void on_signal(int, siginfo_t* info, void*) {
        const int saved = errno;
        CpuProfile* p = active();
        if (p) {
            const std::size_t slot = p->count_.fetch_add(1);
            if (slot < kMaxSamples) {
                p->weights_[slot] = 1 + std::size_t(std::max(info ? info->si_overrun : 0, 0));
                p->depths_[slot] = backtrace(&p->frames_[slot * kDepth], kDepth);
            }
        }
        errno = saved;
    }

    static std::string basename_of(const char* path) {
        if (!path) return "?";
        const char* b = std::strrchr(path, '/');
        return b ? b + 1 : path;
    }

    static std::string demangled(const char* sym) {
        int status = 0;
        char* d = abi::__cxa_demangle(sym, nullptr, nullptr, &status);
        std::string s = status == 0 && d ? d : sym;
        std::free(d);
        // Keep the name, not its argument list.
        const std::size_t paren = s.find('(');
        if (paren != std::string::npos && paren > 0) s.resize(paren);
        return s.size() > 90 ? s.substr(0, 90) + "..." : s;
    }

    static std::string symbol(const Dl& dl, void* addr) {
        if (dl.info.dli_sname) return demangled(dl.info.dli_sname);
        char buf[64];
        std::snprintf(buf, sizeof buf, "+0x%zx",
                      std::size_t(static_cast<char*>(addr) - static_cast<char*>(dl.info.dli_fbase)));
        return buf;
    }

    static std::string library(void* addr) {
        Dl dl;
        if (!dladdr(addr, &dl.info)) return "?";
        return basename_of(dl.info.dli_fname);
    }

    static std::string name(void* addr) {
        Dl dl;
        if (!dladdr(addr, &dl.info)) return "?";
        return basename_of(dl.info.dli_fname) + ": " + symbol(dl, addr);
    }

    static void print_top(std::FILE* out, const char* what, const std::map<std::string, std::size_t>& m,
                          std::size_t n, std::size_t rows) {  // n: the total weight
        std::vector<std::pair<std::size_t, std::string>> v;
        for (const auto& [k, c] : m) v.emplace_back(c, k);
        std::sort(v.rbegin(), v.rend());
        std::fprintf(out, "| %s | share |\n|---|---:|\n", what);
        for (std::size_t i = 0; i < std::min(rows, v.size()); ++i)
            std::fprintf(out, "| %s | %.1f %% |\n", v[i].second.c_str(), 100.0 * double(v[i].first) / double(n));
        std::fprintf(out, "\n");
    }

    std::vector<void*> frames_;
    std::vector<int> depths_;
    std::vector<std::size_t> weights_;  // expiries a signal stands for
    struct sigaction previous_ {};
    std::atomic<std::size_t> count_{0};
    std::vector<timer_t> timers_;
    std::size_t threads_ = 0;
    bool running_ = false;
};

}  // namespace deferred::bench
