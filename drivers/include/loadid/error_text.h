/*
 * One space of return codes for the whole project, and one text for each.
 *
 * Every function returns 0 (or a non-negative count) on success and a
 * negative code on failure: a negated errno (-1..-999), or a private code
 * of the module that returned it, each module in a range of its own:
 *
 *   -1001..-1099  the core (loadid/types.h, LOADID_E_*)
 *   -1101..-1199  the JR3 codec (loadid/jr3.h, LOADID_JR3_E_*)
 *   -1201..-1299  the Modbus F/T driver (loadid/modbus_ft.h)
 *   -1301..-1399  the LCM event-log reader (loadid/lcm_eventlog.h)
 *   -1401..-1499  the LCM wire codecs (loadid/lcm_wire.h)
 *   -1501..-1599  candump lines (loadid/candump.h)
 *
 * Each module's own *_strerror() names its codes; loadid_error_text()
 * names any of them, so that a program need not know which module a code
 * came from.
 */
#ifndef LOADID_ERROR_TEXT_H
#define LOADID_ERROR_TEXT_H

#ifdef __cplusplus
extern "C" {
#endif

/* A static, human-readable text for any return code of the project (0, a
 * negated errno, or a private code of any module). Never NULL. */
const char *loadid_error_text(int code);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_ERROR_TEXT_H */
