// Small text helpers shared by the writers and reports.
#pragma once

#include <string>

namespace navtwin {

/// printf into a std::string (output longer than 1023 characters is cut).
std::string StringPrintf(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// Text for an XML or HTML element or attribute: & < > " ' as entities.
std::string MarkupEscaped(const std::string& text);

}  // namespace navtwin
