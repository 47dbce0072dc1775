/* The daemon's log: one line on stderr, "loadidd: " before it (journald
 * adds the time). The daemon's files print only through this; libraries
 * return codes and reasons instead. */
#ifndef LOADID_DAEMON_LOG_H
#define LOADID_DAEMON_LOG_H

__attribute__((format(printf, 1, 2))) void loadidd_log(const char *fmt, ...);

#endif /* LOADID_DAEMON_LOG_H */
