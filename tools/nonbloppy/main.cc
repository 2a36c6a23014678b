// SPDX-License-Identifier: Apache-2.0
/// @file main.cc
/// @brief `nonbloppy`: particles to surface meshes from the command line.
///
///     nonbloppy mesh IN -o OUT [options]   particles → mesh (and density .vdb)
///     nonbloppy inspect FILE [--json]      what a particle, mesh or .vdb file holds
///     nonbloppy convert IN OUT             particles from one format to another
///     nonbloppy help [COMMAND]             the options of a command
///
/// Every error is one line "nonbloppy: <message>" on stderr; exit codes are 0 (success),
/// 1 (error), 2 (bad command line) and 130 (interrupted).

#include "Commands.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/Version.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <new>
#include <regex>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

namespace nonbloppy_tool {

namespace {

/// @a name as shown in a warning: control bytes would act on the terminal.
std::string shownName(std::string name)
{
    for (char& c : name) {
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
    }
    return name;
}

} // namespace

void warnRenamedAttributes(const std::vector<std::string>& original, const std::vector<std::string>& written,
                           const std::string& path, const WarningPrinter& printer)
{
    for (size_t i = 0; i < original.size() && i < written.size(); ++i) {
        if (written[i].empty() || written[i] == original[i]) continue;
        WarningLine(printer) << "attribute '" << shownName(original[i]) << "' is written to " << path << " as '"
                             << written[i] << "'";
    }
}

void warnRounded(const std::string& name, const std::string& path, const WarningPrinter& printer)
{
    const char* why = lowerExtension(path) == ".vdb" ? "OpenVDB has no 64-bit integer vectors"
                                                     : "PLY has no 64-bit integers";
    WarningLine(printer) << "attribute '" << shownName(name) << "' holds integers past 2^53, which " << path
                         << " stores as doubles, rounded (" << why << "); write .vtk to keep them exact";
}

} // namespace nonbloppy_tool

namespace {

constexpr int kExitError = 1;
constexpr int kExitUsage = 2;

/// CLI11 and OpenVDB messages can span lines; the tool promises one line per error.
std::string oneLine(std::string message)
{
    for (char& c : message) {
        if (c == '\n' || c == '\r' || c == '\t') c = ' ';
    }
    while (!message.empty() && message.back() == ' ') message.pop_back();
    return message;
}

int fail(const std::string& message, int exitCode)
{
    std::cerr << "nonbloppy: " << oneLine(message) << std::endl;
    return exitCode;
}

/// CLI11's "Could not convert: --threads = abc" in the words of the tool's own checks:
/// "--threads needs an integer, got 'abc'". Other messages (and any other spelling a later
/// CLI11 may use) are returned as they are.
std::string conversionMessage(const CLI::App& app, const std::string& message)
{
    const std::string prefix = "Could not convert: ";
    const size_t equals = message.find(" = ", prefix.size());
    if (message.compare(0, prefix.size(), prefix) != 0 || equals == std::string::npos) return message;
    const std::string name = message.substr(prefix.size(), equals - prefix.size());
    const std::string value = message.substr(equals + 3);
    const CLI::Option* option = nullptr;
    for (const CLI::App* command : app.get_subcommands({})) {  // all of them
        if (command->parsed() && (option = command->get_option_no_throw(name))) break;
    }
    if (!option) return message;
    const std::string type = option->get_type_name();
    const bool integer = type == "INT" || type == "UINT";
    // An integer too large for the option's type is one all the same: say so.
    const size_t sign = value.find_first_not_of("+-") == 1 ? 1 : 0;  // one leading sign
    if (integer && value.size() > sign && value.find_first_not_of("0123456789", sign) == std::string::npos) {
        return name + " " + value + " is out of range";
    }
    return name + " needs " + (integer ? "an integer" : "a number") + ", got '" + value + "'";
}

/// CLI11's other refusals in the tool's words, where CLI11 10's spelling is known:
///   "A subcommand is required"               → "unknown command 'frob'; commands are ..."
///   "--output: 1 required TEXT missing"      → "--output needs a value"
///   "--blend: At Most 1 required but received 2" → "--blend given 2 times; give it once"
///   "The following argument was not expected: --bogus" → "mesh has no option '--bogus'; ..."
///   (of several unexpected arguments, the first option given is named, else the first one)
/// Any other message (or a later CLI11's spelling) is returned as it is.
std::string parseMessage(const CLI::App& app, const std::string& message, int argc, char** argv)
{
    const std::string commands = "commands are mesh, inspect, convert, help";
    if (message == "A subcommand is required") {
        if (argc < 2) return "no command given; " + commands;
        const std::string first = argv[1];
        return (first[0] == '-' ? "unknown option '" : "unknown command '") + first + "'; " + commands;
    }
    const CLI::App* command = nullptr;
    for (const CLI::App* c : app.get_subcommands({})) {
        if (c->parsed()) command = c;
    }
    const std::string where = command ? command->get_name() : std::string("nonbloppy");
    const std::string helpHint = "see 'nonbloppy help " + (command ? command->get_name() + "'" : std::string("'"));
    // CLI11 checks the required arguments before it refuses unknown ones: "mesh --bogus"
    // said "IN is required" (hostile-input audit). An unknown option is the first mistake.
    const std::string required = " is required";
    if (command && message.size() > required.size()
        && message.compare(message.size() - required.size(), required.size(), required) == 0) {
        for (const std::string& extra : command->remaining()) {
            if (extra.size() > 1 && extra[0] == '-') return where + " has no option '" + extra + "'; " + helpHint;
        }
    }
    std::smatch match;
    static const std::regex missing(R"(^(\S+): \d+ required (\S+) missing$)");
    static const std::regex repeated(R"(^(\S+): At Most 1 required but received (\d+)$)");
    static const std::regex extra(R"(^The following arguments? (?:was|were) not expected: (.+)$)");
    if (std::regex_match(message, match, missing)) {
        const std::string type = match[2];
        const char* what = (type == "INT" || type == "UINT") ? "an integer" : type == "FLOAT" ? "a number" : "a value";
        return match[1].str() + " needs " + what;
    }
    if (std::regex_match(message, match, repeated)) {
        return match[1].str() + " given " + match[2].str() + " times; give it once";
    }
    if (std::regex_match(message, match, extra)) {
        // CLI11 lists them last first: name the first unknown option given, else the first
        // argument ("--bogus 3" leaves "3 --bogus").
        std::vector<std::string> arguments;
        std::istringstream words(match[1].str());
        for (std::string word; words >> word;) arguments.insert(arguments.begin(), word);
        const auto option = std::find_if(arguments.begin(), arguments.end(),
                                          [](const std::string& a) { return a.size() > 1 && a[0] == '-'; });
        if (option != arguments.end()) return where + " has no option '" + *option + "'; " + helpHint;
        return "unexpected argument '" + arguments.front() + "' to " + where + "; " + helpHint;
    }
    return message;
}

int run(int argc, char** argv)
{
    using namespace nonbloppy_tool;

    CLI::App app("nonbloppy: surface meshes from fluid-simulation particles", "nonbloppy");
    app.set_version_flag("--version", nonbloppy::versionLine(), "Print the version and exit");
    app.require_subcommand(1, 1);
    app.footer("Run 'nonbloppy help COMMAND' or 'nonbloppy COMMAND --help' for a command's "
               "options.");

    // The subcommand table.
    std::vector<Command> commands;
    commands.push_back(setupMeshCommand(app));
    commands.push_back(setupInspectCommand(app));
    commands.push_back(setupConvertCommand(app));

    std::string helpTopic;
    CLI::App* help = app.add_subcommand("help", "Print the options of COMMAND, or this list");
    help->add_option("COMMAND", helpTopic, "mesh, inspect or convert");
    help->footer("");  // not the list's "Run 'nonbloppy help COMMAND' ...", which points back here
    commands.push_back({help, [&]() {
        if (helpTopic.empty()) {
            // Not app.help(): CLI11 hands that to the selected subcommand, "help" itself.
            std::cout << app.get_formatter()->make_help(&app, app.get_name(), CLI::AppFormatMode::Normal);
            return 0;
        }
        for (const Command& command : commands) {
            if (command.app->get_name() == helpTopic) {
                std::cout << command.app->help(app.get_name());
                return 0;
            }
        }
        return fail("unknown command '" + helpTopic + "'; commands are mesh, inspect, convert, help",
                    kExitUsage);
    }});

    try {
        app.parse(argc, argv);
    } catch (const CLI::Success& e) {
        return app.exit(e); // --help or --version: printed on stdout, exit 0
    } catch (const CLI::ConversionError& e) {
        return fail(conversionMessage(app, e.what()), kExitUsage);
    } catch (const CLI::ParseError& e) {
        return fail(parseMessage(app, e.what(), argc, argv), kExitUsage);
    }

    for (const Command& command : commands) {
        if (command.app->parsed()) return command.run();
    }
    return fail("no command given; run 'nonbloppy --help'", kExitUsage);
}

/// std::cout's buffer while a command runs: it hands every write on to C's stdout, as the
/// standard synchronized buffer does (stdio's lock keeps lines from several threads whole),
/// and keeps the errno of the first write that failed. Without it the reason was lost when
/// the failing write was not the last one: `mesh IN -o OUT > /dev/full` flushed its report
/// before the end and said only "cannot write standard output".
class StdoutKeepingFirstError : public std::streambuf
{
public:
    /// errno of the first failed write, or 0.
    int firstError() const { return mFirstError.load(std::memory_order_relaxed); }

protected:
    int_type overflow(int_type c) override
    {
        if (traits_type::eq_int_type(c, traits_type::eof())) return sync() == 0 ? traits_type::not_eof(c) : c;
        if (std::putc(traits_type::to_char_type(c), stdout) == EOF) {
            keep(errno);
            return traits_type::eof();
        }
        return c;
    }

    std::streamsize xsputn(const char* text, std::streamsize count) override
    {
        const size_t written = std::fwrite(text, 1, size_t(count), stdout);
        if (written < size_t(count)) keep(errno);
        return std::streamsize(written);
    }

    int sync() override
    {
        if (std::fflush(stdout) == 0) return 0;
        keep(errno);
        return -1;
    }

private:
    void keep(int error)
    {
        int none = 0;
        if (error != 0) mFirstError.compare_exchange_strong(none, error, std::memory_order_relaxed);
    }

    std::atomic<int> mFirstError{0};
};

/// @a status, or kExitError after one line on stderr if what the command printed on stdout
/// could not all be written (a full disk, a closed descriptor): a script reading
/// `inspect --json > info.json` must not take an empty file for success. A reader that went
/// away (EPIPE, '| head -1') asked for the rest to be dropped, and a failed command has
/// already said why it failed.
int finishStandardOutput(int status, const StdoutKeepingFirstError& output)
{
    errno = 0;
    std::cout.flush();
    const bool lost = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout);
    int error = output.firstError() != 0 ? output.firstError() : errno;
    if (!lost || status != 0) return status;
    // Writes that stdio failed on its own (its buffer filled inside a printf) leave only its
    // error flag. A closed descriptor and a pipe without a reader (POLLERR) can still be
    // told; other causes cannot.
    if (error == 0) {
        pollfd descriptor{STDOUT_FILENO, 0, 0};
        if (::fcntl(STDOUT_FILENO, F_GETFD) == -1) error = errno;
        else if (::poll(&descriptor, 1, 0) == 1 && (descriptor.revents & POLLERR)) error = EPIPE;
    }
    if (error == EPIPE) return status;
    return fail(std::string("cannot write standard output") + (error ? std::string(": ") + std::strerror(error) : ""),
                kExitError);
}

int runCommand(int argc, char** argv)
{
    try {
        return run(argc, argv);
    } catch (const nonbloppy::CancelledError&) {
        return fail("interrupted", nonbloppy_tool::kExitInterrupted);
    } catch (const nonbloppy_tool::UsageError& e) {
        return fail(e.what(), kExitUsage);
    } catch (const nonbloppy::Error& e) {
        return fail(e.what(), kExitError);
    } catch (const openvdb::Exception& e) {
        return fail(e.what(), kExitError);
    } catch (const std::bad_alloc&) {
        return fail("out of memory", kExitError);
    } catch (const std::exception& e) {
        return fail(e.what(), kExitError);
    } catch (...) {
        return fail("unknown error", kExitError);
    }
}

} // namespace

int main(int argc, char** argv)
{
#if defined(__GLIBC__)
    // The program's allocator policy (the library leaves a host application's alone): blocks
    // up to 32 MB come from the heap, and up to 256 MB freed at its top stay there, so the
    // stages reuse each other's memory instead of mapping fresh zeroed pages and unmapping
    // them, which also stalls the other threads (TLB shootdowns). The extraction still hands
    // its freed leaves back (malloc_trim), so peak memory is unchanged. 64x benchmark input,
    // two threads: page faults 140k -> 110k, system time 0.41-0.47 -> 0.26-0.33 s, wall
    // -0.13 s median over 8 alternating pairs (-0.09 s in an earlier set of 8, with the same
    // settings as GLIBC_TUNABLES); peak RSS 322 MB either way.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
    StdoutKeepingFirstError output;
    std::streambuf* const standard = std::cout.rdbuf(&output);
    const int status = finishStandardOutput(runCommand(argc, argv), output);
    std::cout.rdbuf(standard);  // the library's exit-time flush of std::cout must not find a dead buffer
    return status;
}
