#include "core/io/plausibility.h"

#include <sstream>

#include "core/io/input_error.h"

namespace navtwin::plausible {

void Refuse(double value, double lo, double hi, const char* quantity, const char* unit, const std::string& path,
            long line, std::string_view field) {
  std::ostringstream os;
  os << "implausible " << quantity << " " << value << " " << unit << ": outside the plausibility limits [" << lo
     << ", " << hi << "] " << unit << " (core/io/plausibility.h)";
  throw InputError(path, line, std::string(field), os.str());
}

}  // namespace navtwin::plausible
