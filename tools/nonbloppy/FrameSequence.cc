// SPDX-License-Identifier: Apache-2.0
/// @file FrameSequence.cc
/// @brief Frame-number placeholders, `--frames` lists and the plan of a sequence run.

#include "FrameSequence.h"
#include "UsageError.h"

#include <nonbloppy/Error.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <system_error>

namespace nonbloppy_tool {

namespace {

namespace fs = std::filesystem;

/// A --frames list may name at most this many frames (a typo like 1-1000000000 would
/// otherwise allocate gigabytes before anything is checked).
constexpr long long kMaxListedFrames = 10000000;

bool isDigits(const std::string& s)
{
    return !s.empty() && std::all_of(s.begin(), s.end(),
                                     [](char c) { return c >= '0' && c <= '9'; });
}

/// @a number zero-padded to @a width digits.
std::string padded(int number, int width)
{
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%0*d", width, number);
    return buffer;
}

/// A non-negative frame number; nullopt if @a s is not one or does not fit an int.
std::optional<int> parseNumber(const std::string& s)
{
    if (!isDigits(s)) return std::nullopt;
    // Zeros in front are padding, whatever their number ("00000000001" is 1).
    const std::string digits = s.substr(std::min(s.find_first_not_of('0'), s.size() - 1));
    if (digits.size() > 10) return std::nullopt;
    const long long value = std::stoll(digits);
    if (value > INT_MAX) return std::nullopt;
    return static_cast<int>(value);
}

std::string trim(const std::string& s)
{
    size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return s.substr(a, b - a);
}

struct Placeholder
{
    size_t begin = 0, end = 0;   // [begin, end) in the text
    FramePattern::Kind kind = FramePattern::Kind::None;
    int width = 0;
};

/// Every placeholder in @a text from index @a begin on, left to right.
std::vector<Placeholder> findPlaceholders(const std::string& text, size_t begin)
{
    std::vector<Placeholder> found;
    for (size_t i = begin; i < text.size();) {
        if (text.compare(i, 2, "{}") == 0) {
            found.push_back({i, i + 2, FramePattern::Kind::Braces, 0});
            i += 2;
        } else if (text[i] == '#') {
            size_t j = i;
            while (j < text.size() && text[j] == '#') ++j;
            found.push_back({i, j, FramePattern::Kind::Hashes, int(j - i)});
            i = j;
        } else if (text[i] == '%') {
            // %d or %0Nd; anything else after '%' is part of the name.
            size_t j = i + 1;
            int width = 0;
            if (j < text.size() && text[j] == '0') {
                ++j;
                size_t k = j;
                while (k < text.size() && std::isdigit(static_cast<unsigned char>(text[k]))) ++k;
                if (k == j || k - j > 2) { ++i; continue; }
                width = std::stoi(text.substr(j, k - j));
                j = k;
            }
            if (j < text.size() && text[j] == 'd') {
                found.push_back({i, j + 1, FramePattern::Kind::Printf, width});
                i = j + 1;
            } else {
                ++i;
            }
        } else {
            ++i;
        }
    }
    return found;
}

/// Where the file name of @a path begins (after its last '/').
size_t fileNameStart(const std::string& path)
{
    const size_t slash = path.rfind('/');
    return slash == std::string::npos ? 0 : slash + 1;
}

} // namespace

bool placeholderInDirectory(const std::string& path)
{
    const size_t nameStart = fileNameStart(path);
    const std::vector<Placeholder> found = findPlaceholders(path.substr(0, nameStart), 0);
    return !found.empty();
}

FramePattern parseFramePattern(const std::string& text, const std::string& what)
{
    FramePattern pattern;
    pattern.mText = text;
    // Only the file name: a directory is taken as it is spelled ("shot#2/fluid_{}.vtk").
    const std::vector<Placeholder> found = findPlaceholders(text, fileNameStart(text));
    if (found.size() > 1) {
        throw UsageError(what + ": more than one frame placeholder in '" + text
                                        + "'");
    }
    if (found.empty()) return pattern;
    pattern.mKind = found[0].kind;
    pattern.mWidth = found[0].width;
    pattern.mPrefix = text.substr(0, found[0].begin);
    pattern.mSuffix = text.substr(found[0].end);
    return pattern;
}

std::string FramePattern::path(int number) const
{
    switch (mKind) {
    case Kind::None: return mText;
    case Kind::Braces: return mPrefix + std::to_string(number) + mSuffix;
    case Kind::Hashes:
    case Kind::Printf: return mPrefix + padded(number, mWidth) + mSuffix;
    }
    return mText;
}

std::string FramePattern::path(const Frame& frame) const
{
    if (mKind == Kind::Braces) return mPrefix + frame.digits + mSuffix;
    return path(frame.number);
}

std::string FramePattern::directory() const
{
    if (mKind == Kind::None) return fs::path(mText).parent_path().string();
    return fs::path(mPrefix + "0").parent_path().string();
}

std::string FramePattern::directoryPrefix() const
{
    const std::string& text = mKind == Kind::None ? mText : mPrefix;
    const size_t slash = text.rfind('/');
    return slash == std::string::npos ? std::string() : text.substr(0, slash + 1);
}

std::optional<std::string> FramePattern::matchDigits(const std::string& fileName) const
{
    if (mKind == Kind::None) return std::nullopt;
    const std::string prefix = fs::path(mPrefix + "0").filename().string();
    const std::string namePrefix = prefix.substr(0, prefix.size() - 1);
    if (fileName.size() < namePrefix.size() + mSuffix.size() + 1) return std::nullopt;
    if (fileName.compare(0, namePrefix.size(), namePrefix) != 0) return std::nullopt;
    if (fileName.compare(fileName.size() - mSuffix.size(), mSuffix.size(), mSuffix) != 0) {
        return std::nullopt;
    }
    std::string digits = fileName.substr(namePrefix.size(), fileName.size() - namePrefix.size() - mSuffix.size());
    if (!isDigits(digits)) return std::nullopt;
    return digits;
}

std::optional<std::string> FramePattern::matchFileName(const std::string& fileName) const
{
    const std::optional<std::string> matched = matchDigits(fileName);
    if (!matched) return std::nullopt;
    const std::string& digits = *matched;
    const std::optional<int> number = parseNumber(digits);
    if (!number) return std::nullopt;
    // A fixed-width pattern names each frame one way only.
    if (mKind != Kind::Braces && padded(*number, mWidth) != digits) return std::nullopt;
    return digits;
}

std::vector<int> parseFrameList(const std::string& text, const std::string& what)
{
    if (trim(text).empty()) throw UsageError(what + ": empty frame list");
    std::vector<int> frames;
    long long listed = 0;
    size_t start = 0;
    while (true) {
        const size_t comma = text.find(',', start);
        const std::string item = trim(text.substr(start, comma == std::string::npos
                                                             ? std::string::npos : comma - start));
        if (item.empty()) {
            throw UsageError(what + ": empty item in '" + text + "'");
        }

        // item = A | A-B | A-B:S
        std::string range = item, stepText;
        const size_t colon = item.find(':');
        if (colon != std::string::npos) {
            range = trim(item.substr(0, colon));
            stepText = trim(item.substr(colon + 1));
        }
        const size_t dash = range.find('-');
        if (dash == std::string::npos && colon != std::string::npos) {
            throw UsageError(what + ": a step needs a range, as in 1-10:2, got '"
                                            + item + "'");
        }
        const std::optional<int> first = parseNumber(trim(range.substr(0, dash)));
        const std::optional<int> last =
            dash == std::string::npos ? first : parseNumber(trim(range.substr(dash + 1)));
        for (const std::string& number : {trim(range.substr(0, dash)),
                                           dash == std::string::npos ? std::string() : trim(range.substr(dash + 1))}) {
            if (isDigits(number) && !parseNumber(number)) {
                throw UsageError(what + ": frame number " + number + " is past " + std::to_string(INT_MAX)
                                 + ", the largest nonbloppy takes");
            }
        }
        if (!first || !last) {
            throw UsageError(what + ": bad " + std::string(dash == std::string::npos
                                            ? "frame number '" : "range '") + item
                                            + "' (expected N, A-B or A-B:STEP with A, B >= 0)");
        }
        if (*last < *first) {
            throw UsageError(what + ": bad range '" + item + "' (end before start)");
        }
        int step = 1;
        if (colon != std::string::npos) {
            const std::optional<int> s = parseNumber(stepText);
            if (!s && isDigits(stepText)) {
                throw UsageError(what + ": step " + stepText + " is past " + std::to_string(INT_MAX)
                                 + ", the largest nonbloppy takes");
            }
            if (!s || *s < 1) {
                throw UsageError(what + ": bad step in '" + item
                                                + "' (must be an integer >= 1)");
            }
            step = *s;
        }
        listed += (static_cast<long long>(*last) - *first) / step + 1;
        if (listed > kMaxListedFrames) {
            throw UsageError(what + ": more than "
                                            + std::to_string(kMaxListedFrames) + " frames in '"
                                            + text + "'");
        }
        for (long long f = *first; f <= *last; f += step) frames.push_back(static_cast<int>(f));

        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    std::sort(frames.begin(), frames.end());
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
    return frames;
}

std::string formatFrameList(std::vector<int> frames)
{
    std::sort(frames.begin(), frames.end());
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
    std::string out;
    for (size_t i = 0; i < frames.size();) {
        // The longest run from frames[i] with one step: consecutive frames fold from two on
        // ("4-5"), stepped ones from three ("7-11:2"; "5, 7" reads better than "5-7:2").
        size_t j = i;
        const int64_t step = i + 1 < frames.size() ? int64_t(frames[i + 1]) - frames[i] : 1;
        while (j + 1 < frames.size() && int64_t(frames[j + 1]) - frames[j] == step) ++j;
        if (step > 1 && j < i + 2) j = i;
        if (!out.empty()) out += ", ";
        out += std::to_string(frames[i]);
        if (j > i) out += "-" + std::to_string(frames[j]) + (step > 1 ? ":" + std::to_string(step) : "");
        i = j + 1;
    }
    return out;
}

std::vector<Frame> findFrames(const FramePattern& input)
{
    std::string pastLargest;
    return findFrames(input, pastLargest);
}

std::vector<Frame> findFrames(const FramePattern& input, std::string& pastLargest)
{
    pastLargest.clear();
    const std::string dir = input.directory();
    std::error_code ec;
    fs::directory_iterator it(dir.empty() ? fs::path(".") : fs::path(dir), ec);
    if (ec) {
        throw nonbloppy::FileError("cannot read directory " + (dir.empty() ? "." : dir) + ": "
                                   + ec.message());
    }
    std::map<int, Frame> byNumber;
    for (const fs::directory_entry& entry : it) {
        const std::string name = entry.path().filename().string();
        const std::optional<std::string> digits = input.matchFileName(name);
        std::error_code statError;
        if (!digits) {
            // Its digits spell a number past an int: not a frame, but not silently either.
            // (Digits padded otherwise than the pattern's are simply another name.)
            const std::optional<std::string> other = input.matchDigits(name);
            if (other && !parseNumber(*other) && !entry.is_directory(statError)) {
                const std::string path = input.directoryPrefix() + name;
                if (pastLargest.empty() || path < pastLargest) pastLargest = path;
            }
            continue;
        }
        if (entry.is_directory(statError)) continue;
        Frame frame;
        frame.number = *parseNumber(*digits);
        frame.digits = *digits;
        frame.input = input.directoryPrefix() + name;
        const auto [at, inserted] = byNumber.emplace(frame.number, frame);
        if (!inserted) {
            // Directory order is arbitrary: keep the names sorted, so the message is stable.
            std::string a = at->second.input, b = frame.input;
            if (b < a) std::swap(a, b);
            at->second.input = a;
            if (at->second.otherInput.empty() || b < at->second.otherInput) at->second.otherInput = b;
        }
    }
    std::vector<Frame> frames;
    frames.reserve(byNumber.size());
    for (auto& [number, frame] : byNumber) frames.push_back(std::move(frame));
    return frames;
}

FramePlan planFrames(const FramePattern& input, const std::optional<std::vector<int>>& requested)
{
    FramePlan plan;
    std::string pastLargest;
    plan.onDisk = findFrames(input, pastLargest);
    if (!requested && !pastLargest.empty()) {
        throw nonbloppy::FileError(pastLargest + ": its frame number is past " + std::to_string(INT_MAX)
                                   + ", the largest nonbloppy takes; give --frames to leave it out");
    }
    if (!requested) {
        plan.frames = plan.onDisk;
    } else {
        std::map<int, Frame> byNumber;
        for (const Frame& f : plan.onDisk) byNumber.emplace(f.number, f);
        for (int number : *requested) {
            auto it = byNumber.find(number);
            if (it == byNumber.end()) plan.missing.push_back(number);
            else plan.frames.push_back(it->second);
        }
    }
    for (const Frame& frame : plan.frames) {
        if (!frame.otherInput.empty()) {
            throw nonbloppy::FileError(frame.input + " and " + frame.otherInput + " are both frame " +
                                       std::to_string(frame.number));
        }
    }
    return plan;
}

} // namespace nonbloppy_tool
