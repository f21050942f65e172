// Small text helpers shared by the readers of vkmesh's input files (trajectories in vkmesh_base, the dataset
// index and calibration files in vkmesh_io), so that every file is split into lines, parsed into numbers and
// quoted in messages the same way. Internal: the file formats' own functions are in io/trajectory.h and
// io/parsers.h.
#pragma once

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

namespace vkmesh::io::text {

std::string lower(std::string s);

// A number for a message: up to 10 significant digits.
std::string fmt(double v);
std::string fmtFixed(double v, int decimals);
// Timestamps as written in the files: Unix seconds keep their microseconds, frame indices stay integers.
std::string fmtTime(double t);

// "file:line" for messages; the whole path so that the user can open it straight away.
std::string at(const std::filesystem::path& file, size_t line);
std::string at(const std::string& source, size_t line);

std::vector<std::string> splitWhitespace(const std::string& line);
// The tokens joined by single spaces (a line quoted in a message).
std::string joined(const std::vector<std::string>& tokens);

// Locale-independent number parsing (strtod would read "1,5" in a German locale); the whole token must
// be a number, so "1.2abc" is rejected rather than silently read as 1.2.
bool parseNumber(std::string_view tok, double& out);
bool parseInteger(std::string_view tok, long long& out);

struct TextLine {
    size_t number;                    // 1-based, as an editor shows it
    std::vector<std::string> tokens;  // whitespace-separated
};

// The non-blank, non-comment lines of a text file. Blank lines (a trailing newline, CRLF endings) are
// harmless and skipped; '#' starts a comment line as in the TUM files. Throws Error on a read error.
std::vector<TextLine> readDataLines(std::istream& in, const std::string& source);

// Opens a text file for reading; throws Error naming it when it cannot.
std::ifstream openText(const std::filesystem::path& file);

}  // namespace vkmesh::io::text
