// The raw value of a C enum field that came from C code. C lets such a
// field hold any int; C++ makes loading a value outside the enum's range
// undefined (UBSan's -fsanitize=enum reports it), so configuration checks
// read the bytes as the underlying integer instead.
#pragma once

#include <cstring>
#include <type_traits>

namespace loadid {

template <typename E>
std::underlying_type_t<E> enum_value(const E &e) {
    std::underlying_type_t<E> v;
    std::memcpy(&v, &e, sizeof v);
    return v;
}

} // namespace loadid
