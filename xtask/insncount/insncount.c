/*
 * beamfield's instruction counter: a QEMU TCG plugin that counts the guest instructions
 * executed between two marker addresses (the firmware's `bench_mark_start` and
 * `bench_mark_end`, see firmware/src/lib.rs).
 *
 * Every translated instruction gets an inline 64-bit add on one counter, so the count is
 * exact whatever interrupts or exceptions do to a translation block. The two marker
 * instructions also get a callback, which QEMU runs before that instruction's own add: a
 * region therefore counts from the start marker's first instruction (excluded) up to the end
 * marker's first instruction (excluded), and a call of both markers back to back reads as the
 * fixed cost of the calls themselves.
 *
 * Arguments:  -plugin libinsncount.so,start=0xADDR,end=0xADDR   (-d plugin prints the lines)
 * Output:     "insncount: region K: N instructions" per end marker reached (K from 0), then
 *             "insncount: total N" when QEMU exits.
 *
 * Debian ships QEMU's plugin API without its header, so the few entry points used are declared
 * here with the signatures of API version 1 (QEMU 7.2); `cargo xtask` builds this file with
 * gcc when a count is asked for.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t plugin_id;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
struct qemu_info_t;

enum cb_flags { CB_NO_REGS = 0 };
enum inline_op { INLINE_ADD_U64 = 0 };

extern void qemu_plugin_register_vcpu_tb_trans_cb(
    plugin_id, void (*)(plugin_id, struct qemu_plugin_tb *));
extern size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *);
extern struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *, size_t);
extern uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *);
extern void qemu_plugin_register_vcpu_insn_exec_cb(
    struct qemu_plugin_insn *, void (*)(unsigned int, void *), enum cb_flags, void *);
extern void qemu_plugin_register_vcpu_insn_exec_inline(
    struct qemu_plugin_insn *, enum inline_op, void *, uint64_t);
extern void qemu_plugin_register_atexit_cb(plugin_id, void (*)(plugin_id, void *), void *);
extern void qemu_plugin_outs(const char *);

__attribute__((visibility("default"))) int qemu_plugin_version = 1;

/* The guest's single core: one counter, no locking needed. */
static uint64_t executed;
static uint64_t region_start;
static unsigned regions_done;
static int in_region;
/* Thumb addresses: the symbol's low bit is cleared. UINT64_MAX means "not given". */
static uint64_t start_pc = UINT64_MAX;
static uint64_t end_pc = UINT64_MAX;

static void say(const char *text) { qemu_plugin_outs(text); }

static void start_marker(unsigned int vcpu, void *unused) {
    (void)vcpu; (void)unused;
    region_start = executed;
    in_region = 1;
}

static void end_marker(unsigned int vcpu, void *unused) {
    char line[80];
    (void)vcpu; (void)unused;
    if (!in_region) {
        say("insncount: end marker reached outside a region (ignored)\n");
        return;
    }
    in_region = 0;
    snprintf(line, sizeof line, "insncount: region %u: %llu instructions\n", regions_done,
             (unsigned long long)(executed - region_start));
    regions_done++;
    say(line);
}

static void on_translate(plugin_id id, struct qemu_plugin_tb *tb) {
    size_t count = qemu_plugin_tb_n_insns(tb);
    (void)id;
    for (size_t k = 0; k < count; k++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, k);
        uint64_t pc = qemu_plugin_insn_vaddr(insn);
        if (pc == start_pc) {
            qemu_plugin_register_vcpu_insn_exec_cb(insn, start_marker, CB_NO_REGS, NULL);
        } else if (pc == end_pc) {
            qemu_plugin_register_vcpu_insn_exec_cb(insn, end_marker, CB_NO_REGS, NULL);
        }
        qemu_plugin_register_vcpu_insn_exec_inline(insn, INLINE_ADD_U64, &executed, 1);
    }
}

static void on_qemu_exit(plugin_id id, void *unused) {
    char line[64];
    (void)id; (void)unused;
    snprintf(line, sizeof line, "insncount: total %llu\n", (unsigned long long)executed);
    say(line);
}

static int parse_address(const char *arg, const char *key, uint64_t *out) {
    size_t n = strlen(key);
    char *end;
    if (strncmp(arg, key, n) != 0) {
        return 0;
    }
    *out = strtoull(arg + n, &end, 0) & ~(uint64_t)1;
    return *end == '\0' ? 1 : -1;
}

__attribute__((visibility("default"))) int qemu_plugin_install(
    plugin_id id, const struct qemu_info_t *info, int argc, char **argv) {
    (void)info;
    for (int k = 0; k < argc; k++) {
        int got = parse_address(argv[k], "start=", &start_pc);
        if (got == 0) {
            got = parse_address(argv[k], "end=", &end_pc);
        }
        if (got != 1) {
            fprintf(stderr, "insncount: bad argument '%s' (expected start=ADDR or end=ADDR)\n",
                    argv[k]);
            return -1;
        }
    }
    if (start_pc == UINT64_MAX || end_pc == UINT64_MAX || start_pc == end_pc) {
        fprintf(stderr, "insncount: needs two different addresses, start= and end=\n");
        return -1;
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    qemu_plugin_register_atexit_cb(id, on_qemu_exit, NULL);
    return 0;
}
