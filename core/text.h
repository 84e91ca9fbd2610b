// Small text helpers shared by the writers and reports.
#pragma once

#include <cstddef>
#include <string>

namespace navtwin {

/// printf into a std::string (output longer than 1023 characters is cut).
std::string StringPrintf(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// Text for an XML or HTML element or attribute: & < > " ' as entities.
std::string MarkupEscaped(const std::string& text);

/// Text taken from a file, made safe for a message: bytes outside printable ASCII
/// (and the backslash) as \xNN; when `raw` is longer than max_bytes only its first
/// max_bytes are shown, followed by "...".
std::string PrintableText(const std::string& raw, std::size_t max_bytes = 64);

}  // namespace navtwin
