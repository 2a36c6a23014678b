// SPDX-License-Identifier: Apache-2.0
/// @file CliTestUtil.h
/// @brief Running the built `nonbloppy` tool (NONBLOPPY_CLI_PATH) from tests as a user would:
///        a fresh directory per test, captured stdout/stderr, the one-line failure contract,
///        and a spawned run that a test can signal mid-way.

#ifndef NONBLOPPY_CLI_TEST_UTIL_H
#define NONBLOPPY_CLI_TEST_UTIL_H

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace nonbloppy_test {

inline const std::string kCli = NONBLOPPY_CLI_PATH;

inline std::string readText(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline void writeText(const std::string& path, const std::string& text)
{
    std::ofstream out(path, std::ios::binary);
    out << text;
}

/// @a s quoted for /bin/sh.
inline std::string quote(const std::string& s)
{
    std::string out = "'";
    for (char c : s) {
        if (c == '\'') out += "'\\''";
        else out += c;
    }
    return out + "'";
}

inline std::vector<std::string> lines(const std::string& text)
{
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
}

/// Names of the entries of @a dir, sorted.
inline std::vector<std::string> listDir(const std::string& dir)
{
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
}

/// How often @a needle occurs in @a text.
inline size_t count(const std::string& text, const std::string& needle)
{
    size_t n = 0;
    for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
    return n;
}

/// The number after `"key": ` in a JSON text (its first occurrence), NaN when absent.
inline double jsonNumber(const std::string& json, const std::string& key)
{
    const std::string needle = "\"" + key + "\": ";
    const size_t at = json.find(needle);
    if (at == std::string::npos) return std::nan("");
    return std::strtod(json.c_str() + at + needle.size(), nullptr);
}

struct RunResult
{
    int exitCode = -1;  ///< 128 + signal number when the tool was killed by a signal
    int killedBy = 0;   ///< interruptWhen(): the signal that killed the tool, 0 if it exited
    std::string out, err;
};

/// A fresh directory per test, `<TempDir>/nonbloppy_<suite>_<test>_<pid>` with empty
/// subdirectories in/ and out/, removed afterwards.
class CliFixture : public ::testing::Test
{
protected:
    void SetUp() override
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        mDir = (std::filesystem::path(::testing::TempDir())
                / ("nonbloppy_" + std::string(info->test_suite_name()) + "_" + info->name() + "_"
                   + std::to_string(::getpid())))
                   .string();
        std::filesystem::remove_all(mDir);
        std::filesystem::create_directories(mDir + "/in");
        std::filesystem::create_directories(mDir + "/out");
    }
    void TearDown() override
    {
        std::error_code ec;
        std::filesystem::remove_all(mDir, ec);
    }

    std::string dir() const { return mDir; }
    std::string in(const std::string& name) const { return mDir + "/in/" + name; }
    std::string out(const std::string& name) const { return mDir + "/out/" + name; }

    /// Run `nonbloppy ARGS` (ARGS already shell-quoted) with stdout and stderr in files.
    RunResult run(const std::string& args) const { return runAfter("", args); }

    /// run() under `ulimit -v @a kilobytes`, a limit on the address space as a batch
    /// scheduler sets it.
    RunResult runWithAddressLimit(size_t kilobytes, const std::string& args) const
    {
        return runAfter("ulimit -v " + std::to_string(kilobytes) + " && ", args);
    }

    /// run() with the shell command @a prefix before it.
    RunResult runAfter(const std::string& prefix, const std::string& args) const
    {
        const std::string outFile = mDir + "/stdout.txt", errFile = mDir + "/stderr.txt";
        const std::string command = prefix + quote(kCli) + " " + args + " >" + quote(outFile) + " 2>"
                                    + quote(errFile) + " </dev/null";
        const int status = std::system(command.c_str());
        RunResult result;
        result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        result.out = readText(outFile);
        result.err = readText(errFile);
        return result;
    }

protected:
    /// The failure contract: exit @a exitCode (1: an error, 2: a bad command line), exactly
    /// one stderr line, equal to "nonbloppy: " + @a message, and nothing (not even a
    /// temporary file) in out/.
    void expectFailure(const std::string& args, const std::string& message, int exitCode = 1) const
    {
        SCOPED_TRACE(args);
        const RunResult r = run(args);
        EXPECT_EQ(r.exitCode, exitCode);
        const std::vector<std::string> errLines = lines(r.err);
        ASSERT_EQ(errLines.size(), 1u) << r.err;
        EXPECT_EQ(errLines[0], "nonbloppy: " + message);
        EXPECT_TRUE(listDir(mDir + "/out").empty()) << "output files left behind";
    }

    /// expectFailure() for a bad command line: exit 2 (docs/farm.md), before any work.
    void expectUsageError(const std::string& args, const std::string& message) const
    {
        expectFailure(args, message, 2);
    }

    /// Starts `nonbloppy ARGS` (unquoted arguments) with stdout to /dev/null and stderr to
    /// @a errFile; returns its pid, or 0 (a failure added) if it could not be started. The
    /// stop signals start at their default action and unblocked, as from a terminal, whatever
    /// the suite inherited: under `nohup` SIGHUP is ignored, which the tool keeps (as nohup
    /// means it to), and the SIGHUP test failed; a background job of a script ignores SIGINT.
    pid_t spawnCli(const std::vector<std::string>& args, const std::string& errFile) const
    {
        std::vector<std::string> full = {kCli};
        full.insert(full.end(), args.begin(), args.end());
        std::vector<char*> argv;
        for (const std::string& a : full) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
        posix_spawn_file_actions_addopen(&actions, 2, errFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        posix_spawnattr_t attributes;
        posix_spawnattr_init(&attributes);
        sigset_t defaults, none;
        sigemptyset(&defaults);
        for (const int signal : {SIGHUP, SIGINT, SIGTERM}) sigaddset(&defaults, signal);
        sigemptyset(&none);
        posix_spawnattr_setsigdefault(&attributes, &defaults);
        posix_spawnattr_setsigmask(&attributes, &none);
        posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
        pid_t pid = 0;
        const int spawned = posix_spawn(&pid, kCli.c_str(), &actions, &attributes, argv.data(), environ);
        posix_spawnattr_destroy(&attributes);
        posix_spawn_file_actions_destroy(&actions);
        if (spawned != 0) ADD_FAILURE() << "posix_spawn failed: " << spawned;
        return spawned == 0 ? pid : 0;
    }

    /// Waits for @a pid: its exit status, or 128 + the signal that ended it (also stored in
    /// @a killedBy, 0 for an exit).
    static int waitForExit(pid_t pid, int* killedBy = nullptr)
    {
        int status = 0;
        if (::waitpid(pid, &status, 0) != pid) ADD_FAILURE() << "waitpid failed";
        if (killedBy) *killedBy = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }

    /// Starts `nonbloppy ARGS` (unquoted arguments) with stdout to /dev/null and stderr to
    /// stderr.txt; waits until @a ready holds for that stderr (at most 30 s), sends @a signal
    /// @a times times, @a gap apart, and waits for the exit. Returns how it ended and the
    /// stderr text.
    RunResult interruptWhen(const std::vector<std::string>& args,
                            const std::function<bool(const std::string& err)>& ready, int signal,
                            int times = 1, std::chrono::milliseconds gap = std::chrono::milliseconds(0)) const
    {
        const std::string errFile = mDir + "/stderr.txt";
        RunResult result;
        const pid_t pid = spawnCli(args, errFile);
        if (pid == 0) return result;
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
        while (!ready(readText(errFile)) && std::chrono::steady_clock::now() < deadline) {
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
        for (int n = 0; n < times; ++n) {
            if (n > 0) std::this_thread::sleep_for(gap);
            ::kill(pid, signal);
        }
        result.exitCode = waitForExit(pid, &result.killedBy);
        result.err = readText(errFile);
        return result;
    }

private:
    std::string mDir;
};

} // namespace nonbloppy_test

#endif // NONBLOPPY_CLI_TEST_UTIL_H
