/*
 * A small YAML document tree with line numbers, on libyaml's event API:
 * the configuration (config.c) and the project's other YAML files
 * (trajectories, truth.yaml) are read through it.
 *
 * A document is mappings, sequences and scalars; every node knows its
 * 1-based line and its path from the root ("jr3.full_scale.force",
 * "estimation.methods[1]": keys joined by '.', sequence items by a 0-based
 * [index], "(top level)" for the root), so that every error reads
 *   "FILE:LINE: PATH: what is wrong"
 * on one line (control characters in it are replaced by '?').
 *
 * Reading is strict where a silent surprise would cost more than an error:
 *   - a key twice in one mapping is an error ("duplicate key (first on
 *     line N)"); keys must be scalars;
 *   - aliases (*name) are refused: no file of this project needs them and
 *     a tree without them has no shared nodes; anchors alone are ignored;
 *   - one document per file (a second "---" document is an error);
 *   - nesting deeper than LOADID_YAML_MAX_DEPTH, or a file larger than
 *     LOADID_YAML_MAX_BYTES, is refused.
 * Typed conversions follow the YAML 1.2 core schema, restricted:
 *   - numbers are plain scalars (a quoted "1.5" is a string, not a number):
 *     decimal integers or decimal floats ([-+]?(.d+|d+(.d*)?)([eE][-+]?d+)?);
 *     .nan, .inf and their spellings are refused as not finite;
 *   - integers: decimal or hexadecimal (0x1A0), no octal, no underscores;
 *   - booleans: true, True, TRUE, false, False, FALSE (not YAML 1.1's yes/no);
 *   - null: an empty plain scalar, ~, null, Null, NULL;
 *   - an explicit !!str tag makes a plain scalar a string; other tags are
 *     ignored.
 * Numbers are converted with strtod/strtoll, which follow LC_NUMERIC: the
 * programs keep the "C" locale (they never call setlocale).
 *
 * Return convention (loadid/error_text.h): 0 or a count on success, a negative errno on
 * failure. The loadid_yaml_get_* getters return 1 when the key is present
 * and *out was written, 0 when it is absent (or map is NULL: an absent
 * section), and -EINVAL when it is present but wrong, with the message in
 * loadid_yaml_error(). A getter that fails leaves *out unchanged, except
 * for the arrays, whose contents are then unspecified.
 *
 * Lookups mark a key as used and remember, in each mapping, every key a
 * reader asked for (present or not); loadid_yaml_report_unused and
 * loadid_yaml_each_unused then name every key no reader asked for (an
 * unknown key, or a typo) with the asked-for key closest to it.
 */
#ifndef LOADID_YAML_TREE_H
#define LOADID_YAML_TREE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define LOADID_YAML_MAX_DEPTH 64                  /* nested collections */
#define LOADID_YAML_MAX_BYTES (64u * 1024 * 1024) /* size of one file */

typedef enum {
    LOADID_YAML_SCALAR = 1,
    LOADID_YAML_SEQUENCE = 2,
    LOADID_YAML_MAPPING = 3
} loadid_yaml_kind_t;

typedef struct loadid_yaml_doc loadid_yaml_doc_t;   /* opaque */
typedef struct loadid_yaml_node loadid_yaml_node_t; /* opaque, owned by its doc */

/* --- Loading ------------------------------------------------------------ */

/* Reads and parses the file at path. On success *out is the document (free
 * it with loadid_yaml_free) and 0 is returned. On failure *out is NULL, err
 * holds one line, and the return is:
 *   -errno (e.g. -ENOENT, -EISDIR, -EFBIG): "PATH: cannot read: reason";
 *   -EINVAL: "PATH:LINE: KEY: syntax error: ..." (libyaml's problem, the
 *            path of the innermost node open at the error), or a duplicate
 *            key, an alias, a second document, too deep a nesting;
 *   -ENOMEM: out of memory. */
int loadid_yaml_load_file(const char *path, loadid_yaml_doc_t **out, char *err, size_t errlen);

/* The same on text (len bytes, need not be NUL-terminated); name stands for
 * the file name in messages. Returns 0, -EINVAL or -ENOMEM. */
int loadid_yaml_load_string(const char *name, const char *text, size_t len, loadid_yaml_doc_t **out,
                            char *err, size_t errlen);

void loadid_yaml_free(loadid_yaml_doc_t *doc);

/* The root node; NULL for an empty document (no content, only comments, or
 * a lone null scalar such as "~"). */
loadid_yaml_node_t *loadid_yaml_root(const loadid_yaml_doc_t *doc);

/* The file name given at load. */
const char *loadid_yaml_file(const loadid_yaml_doc_t *doc);

/* The last error message (one line, "" when none). */
const char *loadid_yaml_error(const loadid_yaml_doc_t *doc);

/* --- Nodes ---------------------------------------------------------------- */

loadid_yaml_kind_t loadid_yaml_kind(const loadid_yaml_node_t *node);
int loadid_yaml_line(const loadid_yaml_node_t *node); /* 1-based */

/* Items of a sequence, or key/value pairs of a mapping; 0 for a scalar. */
size_t loadid_yaml_count(const loadid_yaml_node_t *node);

/* Item i of a sequence; NULL when node is not a sequence or i is out of
 * range. */
loadid_yaml_node_t *loadid_yaml_item(const loadid_yaml_node_t *node, size_t i);

/* Key (a scalar node) and value of pair i of a mapping, in file order;
 * NULL when node is not a mapping or i is out of range. Neither marks the
 * key as used (loadid_yaml_mark_used does). */
loadid_yaml_node_t *loadid_yaml_key_at(const loadid_yaml_node_t *node, size_t i);
loadid_yaml_node_t *loadid_yaml_value_at(const loadid_yaml_node_t *node, size_t i);

/* A scalar's text (NUL-terminated; it may hold further NULs from "\0"
 * escapes, *len says, len may be NULL); NULL for a collection. */
const char *loadid_yaml_scalar(const loadid_yaml_node_t *node, size_t *len);

/* 1 for a null scalar (see above), else 0. */
int loadid_yaml_is_null(const loadid_yaml_node_t *node);

/* The node's path ("a.b[2].c"; "(top level)" for the root) into buf,
 * truncated to len - 1 characters. Returns the untruncated length. */
size_t loadid_yaml_path(const loadid_yaml_node_t *node, char *buf, size_t len);

/* The value of key in mapping map, marked as used; NULL when map is NULL,
 * not a mapping, or has no such key. Either way map remembers key as one
 * its reader knows (for loadid_yaml_suggest). */
loadid_yaml_node_t *loadid_yaml_get(loadid_yaml_node_t *map, const char *key);

/* Marks the value node of a mapping pair as used (for readers that iterate
 * with loadid_yaml_value_at). */
void loadid_yaml_mark_used(loadid_yaml_node_t *value);

/* --- Errors and warnings -------------------------------------------------- */

/* Formats "FILE:LINE: PATH: <fmt ...>" for node as the document's error and
 * returns -EINVAL, for checks of a reader's own ("must be > 0"). */
int loadid_yaml_fail(const loadid_yaml_node_t *node, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* A key no lookup asked for. */
typedef struct {
    const loadid_yaml_node_t *key; /* the key (a scalar) */
    const loadid_yaml_node_t *map; /* the mapping holding it (the root for a
                                        top-level key) */
    const char *suggestion;        /* loadid_yaml_suggest(map, key), or NULL */
} loadid_yaml_unused_t;

/* Calls fn(ctx, &u) for every mapping key, in file order, that no lookup
 * asked for, without descending into its value; values that were used are
 * searched, through sequences too. fn may be NULL. Returns the number of
 * such keys. */
int loadid_yaml_each_unused(const loadid_yaml_doc_t *doc,
                            void (*fn)(void *ctx, const loadid_yaml_unused_t *u), void *ctx);

/* The same as one line each: fn(ctx, "FILE:LINE: PATH: unknown key,
 * ignored"), with " (did you mean 'KEY'?)" after it when a known key is
 * close. */
int loadid_yaml_report_unused(const loadid_yaml_doc_t *doc, void (*fn)(void *ctx, const char *msg),
                              void *ctx);

/* Of the keys a reader asked for in mapping map, the one closest to text
 * by edit distance (insertions, deletions, substitutions and swaps of two
 * neighbours, 1 each) within 1 edit for a known key of up to 4 characters,
 * 2 up to 8 and 3 beyond, and fewer edits than text has characters; the
 * first asked of equally close ones. NULL when none is that close, or map
 * is not a mapping. The string lives as long as the document. */
const char *loadid_yaml_suggest(const loadid_yaml_node_t *map, const char *text);

/* The keys a reader asked for in map, in the order asked, joined by ", "
 * into buf (truncated to len - 1 characters; "" for none). Returns the
 * untruncated length. */
size_t loadid_yaml_known_keys(const loadid_yaml_node_t *map, char *buf, size_t len);

/* --- Typed conversions of one node ---------------------------------------- */
/* Each returns 0, or -EINVAL with "FILE:LINE: PATH: expected ..., got ..."
 * as the document's error; *out is written only on success. */

/* A finite double: a plain decimal integer or float. */
int loadid_yaml_as_double(const loadid_yaml_node_t *node, double *out);
/* An int: plain decimal or 0x hexadecimal, optionally signed, in int range. */
int loadid_yaml_as_int(const loadid_yaml_node_t *node, int *out);
/* A uint64_t: plain decimal or 0x hexadecimal, no '-' sign. */
int loadid_yaml_as_uint64(const loadid_yaml_node_t *node, uint64_t *out);
/* A boolean: true/false (also True, TRUE, False, FALSE); *out 1 or 0. */
int loadid_yaml_as_bool(const loadid_yaml_node_t *node, int *out);
/* A string of at most size - 1 bytes into buf (NUL-terminated): any
 * non-null scalar, quoted or plain ("123" is a valid string); no NUL
 * inside. */
int loadid_yaml_as_string(const loadid_yaml_node_t *node, char *buf, size_t size);
/* A sequence of min..max finite numbers into out (max of them), *count how
 * many (count may be NULL when min == max). "expected 3 numbers, got 2"
 * when min == max, else "expected at least/at most N numbers, got M";
 * an item that is not a finite number fails at that item's own path and
 * line ("key[2]: expected a number, got 'x'"). */
int loadid_yaml_as_doubles(const loadid_yaml_node_t *node, double *out, size_t min, size_t max,
                           size_t *count);

/* --- Getters: lookup + conversion (1 read, 0 absent, -EINVAL wrong) -------- */

/* A nested mapping: *out is the mapping, or NULL when the key is absent or
 * its value is null (an empty section: every key in it absent). */
int loadid_yaml_get_mapping(loadid_yaml_node_t *map, const char *key, loadid_yaml_node_t **out);
/* A sequence node (a null value is an error here: "expected a sequence"). */
int loadid_yaml_get_sequence(loadid_yaml_node_t *map, const char *key, loadid_yaml_node_t **out);
int loadid_yaml_get_double(loadid_yaml_node_t *map, const char *key, double *out);
int loadid_yaml_get_int(loadid_yaml_node_t *map, const char *key, int *out);
int loadid_yaml_get_uint64(loadid_yaml_node_t *map, const char *key, uint64_t *out);
int loadid_yaml_get_bool(loadid_yaml_node_t *map, const char *key, int *out);
int loadid_yaml_get_string(loadid_yaml_node_t *map, const char *key, char *buf, size_t size);
/* Exactly n numbers. */
int loadid_yaml_get_doubles(loadid_yaml_node_t *map, const char *key, double *out, size_t n);
/* min..max numbers, *count of them. */
int loadid_yaml_get_double_seq(loadid_yaml_node_t *map, const char *key, double *out, size_t min,
                               size_t max, size_t *count);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_YAML_TREE_H */
