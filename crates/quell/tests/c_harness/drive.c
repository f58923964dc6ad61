/* Drives a generated f32 controller (prefix quell) with 20,000 steps of pseudo-random y, g in
 * [-2, 2) and prints the bits of u_f every 2,000 steps and a hash of all of them. Built for the
 * host (printf) and for a Cortex-M4F run under qemu-system-arm -M mps2-an386 (semihosting), so
 * that the two outputs can be compared bit for bit. */
#include <stddef.h>
#include <stdint.h>
#include "quell_controller.h"

static quell_state s;
static uint32_t lcg = 12345u;

/* Uniform in [-2, 2), exactly the same float on every IEEE machine. */
static float next(void)
{
    lcg = lcg * 1664525u + 1013904223u;
    return (float)(lcg >> 8) / 4194304.0f - 2.0f;
}

static uint32_t bits(float x)
{
    union { float f; uint32_t u; } v;
    v.f = x;
    return v.u;
}

static void emit(const char *label, uint32_t value);

static void drive(void)
{
    float y[QUELL_M], g[QUELL_M], u_f[QUELL_M];
    uint32_t hash = 2166136261u;
    quell_init(&s);
    for (long k = 0; k < 20000; k++) {
        for (unsigned i = 0; i < QUELL_M; i++) {
            y[i] = next();
            g[i] = next();
        }
        quell_step(&s, y, g, u_f);
        for (unsigned i = 0; i < QUELL_M; i++)
            hash = (hash ^ bits(u_f[i])) * 16777619u;
        if (k % 2000 == 0)
            emit("u_f[0]", bits(u_f[0]));
    }
    emit("hash", hash);
}

#ifdef __arm__
/* Bare metal: a vector table, a reset handler that sets up RAM and the FPU, and output through
 * semihosting (SYS_WRITE0, then SYS_EXIT). */
extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
void Reset_Handler(void);
void Default_Handler(void);

static int semihost(int op, const void *arg)
{
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

static void emit(const char *label, uint32_t value)
{
    char line[40];
    unsigned n = 0;
    while (*label)
        line[n++] = *label++;
    line[n++] = ' ';
    for (int i = 7; i >= 0; i--)
        line[n++] = "0123456789abcdef"[(value >> (4 * i)) & 15u];
    line[n++] = '\n';
    line[n] = 0;
    semihost(0x04, line);
}

void *memset(void *d, int c, size_t n)
{
    unsigned char *p = d;
    while (n--)
        *p++ = (unsigned char)c;
    return d;
}

void *memcpy(void *d, const void *src, size_t n)
{
    unsigned char *p = d;
    const unsigned char *q = src;
    while (n--)
        *p++ = *q++;
    return d;
}

void Reset_Handler(void)
{
    uint32_t *src = &_sidata, *dst = &_sdata;
    while (dst < &_edata)
        *dst++ = *src++;
    for (dst = &_sbss; dst < &_ebss;)
        *dst++ = 0;
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20; /* CPACR: CP10, CP11 on (the FPU) */
    __asm__ volatile("dsb\n\tisb");
    drive();
    semihost(0x18, (const void *)0x20026u); /* ADP_Stopped_ApplicationExit */
    for (;;) {
    }
}

void Default_Handler(void)
{
    for (;;) {
    }
}

__attribute__((section(".isr_vector"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))&_estack, Reset_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, Default_Handler, Default_Handler,
};
#else
#include <stdio.h>

static void emit(const char *label, uint32_t value)
{
    printf("%s %08lx\n", label, (unsigned long)value);
}

int main(void)
{
    drive();
    return 0;
}
#endif
