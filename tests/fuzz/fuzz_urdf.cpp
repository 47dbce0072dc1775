// Fuzz target urdf: the URDF loader (firmware/urdf/urdf_chain.cpp on
// urdfdom and TinyXML) from text, as loadidd reads robot.urdf, for the
// chain from base_link to ft_sensor (the shipped configuration's links).
// Beyond the sanitizers it checks what loadid/urdf.h promises: a chain
// that passes loadid_chain_check with the links asked for, or
// LOADID_E_MODEL with a one-line reason (no control characters) that
// names the file; exceptions must not escape the C API (one would end the
// run). And that every model urdfdom hands over is freed (see below).
#include <cstring>
#include <string>

#include "fuzz_check.h"
#include "loadid/types.h"
#include "loadid/urdf.h"

// The sanitizer runtime's heap in use [bytes]; absent (null) without ASan.
extern "C" size_t __sanitizer_get_current_allocated_bytes() __attribute__((weak));

// urdfdom 3.0 (Debian 12) itself leaks the links of a document whose joints
// form a cycle when it refuses it (no root link: parseURDF drops a model
// whose links own each other), which is not ours to fix: LeakSanitizer
// ignores what parseURDF allocates. So that this hides nothing of the
// loader's own, the harness checks below that the heap in use is the same
// after every load in which parseURDF returned a model.
extern "C" const char *__lsan_default_suppressions() {
    return "leak:urdf::parseURDF\n";
}

namespace {
constexpr char kName[] = "robot.urdf";
constexpr char kNotUrdf[] = "robot.urdf: not a valid URDF:"; // parseURDF gave no model

int load(const char *xml, loadid_chain_t *chain, char (&err)[512]) {
    return loadid_urdf_load_string(xml, kName, "base_link", "ft_sensor", chain, err, sizeof err);
}
} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size > 256 * 1024) return 0; // a robot's URDF is a few KB; keeps runs fast
    static bool warm = false;
    loadid_chain_t chain;
    char err[512] = "";
    if (!warm) { // what the libraries allocate once (console_bridge, locales)
        load("<robot name='r'><link name='base_link'/></robot>", &chain, err);
        warm = true;
    }
    const std::string xml(reinterpret_cast<const char *>(data), size); // NUL-terminated
    std::memset(&chain, 0x5A, sizeof chain);
    err[0] = '\0';
    const size_t heap_before =
        __sanitizer_get_current_allocated_bytes ? __sanitizer_get_current_allocated_bytes() : 0;
    const int rc = load(xml.c_str(), &chain, err);
    const size_t heap_after =
        __sanitizer_get_current_allocated_bytes ? __sanitizer_get_current_allocated_bytes() : 0;

    FUZZ_CHECK(std::memchr(err, '\0', sizeof err) != nullptr);
    for (const char *c = err; *c; ++c) FUZZ_CHECK(static_cast<unsigned char>(*c) >= 0x20);
    const bool no_model = std::strncmp(err, kNotUrdf, sizeof kNotUrdf - 1) == 0;
    if (!no_model) FUZZ_CHECK(heap_after == heap_before); // the model was freed
    if (rc != 0) {
        FUZZ_CHECK(rc == LOADID_E_MODEL);
        FUZZ_CHECK(std::strncmp(err, "robot.urdf: ", 12) == 0 && err[12] != '\0');
        return 0;
    }
    FUZZ_CHECK(err[0] == '\0');
    FUZZ_CHECK(loadid_chain_check(&chain) == 0);
    FUZZ_CHECK(std::strcmp(chain.base_link, "base_link") == 0);
    FUZZ_CHECK(std::strcmp(chain.sensor_link, "ft_sensor") == 0);
    return 0;
}
