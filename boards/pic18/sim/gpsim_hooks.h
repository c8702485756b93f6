/* EasyLab PIC18 board: what the programs that run firmware in libgpsim
 * share (the harness, sim/pic18_sim.cc; the benchmark's runner,
 * bench/bench_pic18.py): a register that reports writes, and quiet stdout
 * while libgpsim sets up. */
#ifndef GPSIM_HOOKS_H
#define GPSIM_HOOKS_H

#include <gpsim/processor.h>
#include <gpsim/registers.h>

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>

/* A register in front of gpsim's own (gpsim looks registers up by address
 * at every access): every access passes on, writes are reported to
 * `on_write(address, value)` in the middle of the instruction. */
class HookRegister : public Register {
public:
    HookRegister(Processor *p, Register *original, void (*report)(unsigned, unsigned))
        : Register(p, original->name().c_str(), "EasyLab hook"), orig(original), on_write(report)
    {
        address = original->address;
    }
    unsigned int get() override { return orig->get(); }
    unsigned int get_value() override { return orig->get_value(); }
    void put(unsigned int v) override
    {
        orig->put(v);
        on_write(address, v & 0xFFu);
    }
    void put_value(unsigned int v) override { orig->put_value(v); }
    RegisterValue getRV() override { return orig->getRV(); }
    void putRV(RegisterValue rv) override
    {
        orig->putRV(rv);
        on_write(address, rv.data & 0xFFu);
    }
    RegisterValue getRV_notrace() override { return orig->getRV_notrace(); }
    void putRV_notrace(RegisterValue rv) override { orig->putRV_notrace(rv); }
    RegisterValue getRVN() override { return orig->getRVN(); }
    RegisterValue getRVN_notrace() override { return orig->getRVN_notrace(); }
    void setbit(unsigned int bit, bool v) override { orig->setbit(bit, v); }
    bool get_bit(unsigned int bit) override { return orig->get_bit(bit); }
    double get_bit_voltage(unsigned int bit) override { return orig->get_bit_voltage(bit); }
    Register *getReg() override { return orig; }
    REGISTER_TYPES isa() override { return orig->isa(); }

private:
    Register *orig;
    void (*on_write)(unsigned, unsigned);
};

/* libgpsim prints on stdout while it loads and sets up: keep ours clean. */
class QuietStdout {
public:
    QuietStdout()
    {
        fflush(stdout);
        saved = dup(1);
        int null = open("/dev/null", O_WRONLY);
        if (null >= 0) {
            dup2(null, 1);
            close(null);
        }
    }
    ~QuietStdout()
    {
        fflush(stdout);
        if (saved >= 0) {
            dup2(saved, 1);
            close(saved);
        }
    }

private:
    int saved;
};

#endif /* GPSIM_HOOKS_H */
