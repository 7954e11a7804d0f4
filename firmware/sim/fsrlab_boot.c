/*
 * fsrlab_boot: an Uno as avrdude sees it — an ATmega328P at 16 MHz in simavr running the Uno's
 * bootloader (optiboot, an Intel hex file) from the boot section at 0x7E00, its USART0 on a file
 * descriptor (the master side of a pseudo-terminal the caller owns). avrdude uploads through it as
 * through a real board; the bootloader then resets into what it wrote, and that firmware talks on the
 * same fd. Used by the tests of `fsrlab firmware flash`.
 *
 * Usage:
 *   fsrlab_boot BOOTLOADER.hex --uart-fd N [--flash-out FILE]
 *
 * The reset: an Uno's bootloader stays only after an external reset (optiboot: MCUSR.EXTRF), which
 * on the board is avrdude's DTR pulse through a capacitor. A pseudo-terminal has no DTR, so the MCU is
 * held in reset until the host's first byte arrives, and then starts with MCUSR = EXTRF: the first
 * byte stands for the pulse (it is still delivered, as avrdude's first sync arrives after its pulse).
 * After the upload optiboot lets the watchdog reset the MCU (MCUSR = WDRF) and jumps to the
 * application, as on the board.
 *
 * Time: simulated time is held to the wall clock (never ahead of it): optiboot's watchdog (1 s without
 * a byte) and avrdude's timeouts are both in real seconds.
 *
 * Output on stderr, one line each:
 *   #READY                    bootloader loaded, held in reset until the first byte
 *   #RESET <cycle> <mcusr>    the MCU left reset (MCUSR as the reset left it: 2 external, 8 watchdog)
 *   #END <cycles>             stdin closed; with --flash-out the whole flash (32 KiB) was written
 * The process ends when stdin closes (its caller ended or died).
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdint.h>
#include <unistd.h>
#include <fcntl.h>
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <time.h>

#include <sim_avr.h>
#include <sim_irq.h>
#include <sim_io.h>
#include <avr_uart.h>

#define F_CPU_HZ 16000000u
#define BYTE_CYCLES 1389u /* one UART byte at 115200 baud, 10 bits */
#define TICK_CYCLES 16000u /* 1 ms: the pacing step */
#define BOOT_START 0x7E00u /* optiboot on the ATmega328P: the 512-byte boot section (BOOTRST fuse set) */
#define MCUSR_ADDR 0x54
#define EXTRF 0x02
#define UCSR0A_ADDR 0xC0
#define UDRE0 0x20

static avr_t *avr;
static avr_irq_t *uart_in;
static int uart_fd = -1;

static uint8_t obuf[4096];
static size_t olen;
static uint8_t ibuf[4096];
static size_t ihead, itail;

static void flush_out(void) {
  size_t off = 0;
  while (off < olen) {
    ssize_t n = write(uart_fd, obuf + off, olen - off);
    if (n > 0) { off += (size_t)n; continue; }
    if (n < 0 && errno == EINTR) continue;
    break; /* nobody reads: lost, as on a UART */
  }
  olen = 0;
}

static void uart_out_cb(struct avr_irq_t *irq, uint32_t value, void *param) {
  (void)irq; (void)param;
  if (olen == sizeof obuf) flush_out();
  obuf[olen++] = (uint8_t)value;
}

/* UDRE0 is 1 after a reset and stays 1 while nothing is being sent; simavr 1.6 can leave it clear
 * after a write to UCSR0A (both the bootloader and the firmware write U2X0), and a polled putch would
 * then wait forever. Every write to UCSR0A sets it again (a shared I/O write hook survives resets,
 * simavr's cycle timers do not). */
static void ucsr0a_write(struct avr_t *a, avr_io_addr_t addr, uint8_t v, void *param) {
  (void)addr; (void)v; (void)param;
  a->data[UCSR0A_ADDR] |= UDRE0;
}

static int read_uart(void) {
  int got = 0;
  while (itail - ihead < sizeof ibuf) {
    size_t room = sizeof ibuf - (itail - ihead);
    size_t pos = itail % sizeof ibuf;
    size_t n = room < sizeof ibuf - pos ? room : sizeof ibuf - pos;
    ssize_t r = read(uart_fd, ibuf + pos, n);
    if (r <= 0) break;
    itail += (size_t)r;
    got = 1;
  }
  return got;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int stdin_eof;

/* Wait up to timeout_ms for host bytes or the end of stdin. */
static void wait_io(int timeout_ms) {
  struct pollfd p[2] = {{0, POLLIN, 0}, {uart_fd, POLLIN, 0}};
  if (poll(p, 2, timeout_ms) <= 0) return;
  if (p[1].revents & POLLIN) read_uart();
  if (p[0].revents & (POLLIN | POLLHUP)) {
    char b[256];
    ssize_t n = read(0, b, sizeof b);
    if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN)) stdin_eof = 1;
  }
}

/* Intel hex into the flash. simavr's reader refuses the start-address record (type 03) that
 * Debian's optiboot hex carries, hence this one: types 00 data, 01 end, 02/04 address bases; 03/05
 * (start addresses) ignored. Every checksum is checked. */
static int hexval(const char *s, int n) {
  int v = 0;
  for (int i = 0; i < n; i++) {
    char c = s[i];
    int d = c >= '0' && c <= '9' ? c - '0' : c >= 'A' && c <= 'F' ? c - 'A' + 10 : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
    if (d < 0) return -1;
    v = v * 16 + d;
  }
  return v;
}

static int load_hex(const char *path) {
  FILE *f = fopen(path, "r");
  if (!f) { fprintf(stderr, "cannot read %s\n", path); return -1; }
  char line[600];
  uint32_t base = 0;
  int lineno = 0;
  while (fgets(line, sizeof line, f)) {
    lineno++;
    size_t len = strcspn(line, "\r\n");
    if (len == 0) continue;
    int n = len >= 11 && line[0] == ':' ? hexval(line + 1, 2) : -1;
    if (n < 0 || len != (size_t)(11 + 2 * n)) goto bad;
    uint8_t sum = 0, rec[256 + 5];
    for (int i = 0; i < n + 5; i++) {
      int b = hexval(line + 1 + 2 * i, 2);
      if (b < 0) goto bad;
      rec[i] = (uint8_t)b;
      sum += (uint8_t)b;
    }
    if (sum != 0) goto bad;
    uint32_t addr = ((uint32_t)rec[1] << 8) | rec[2];
    switch (rec[3]) {
    case 0:
      if (base + addr + n > avr->flashend + 1) { fprintf(stderr, "%s:%d: beyond the flash\n", path, lineno); fclose(f); return -1; }
      memcpy(avr->flash + base + addr, rec + 4, n);
      break;
    case 1: fclose(f); return 0;
    case 2: base = (((uint32_t)rec[4] << 8) | rec[5]) << 4; break;
    case 4: base = (((uint32_t)rec[4] << 8) | rec[5]) << 16; break;
    default: break;
    }
  }
  fclose(f);
  fprintf(stderr, "%s: no end record\n", path);
  return -1;
bad:
  fclose(f);
  fprintf(stderr, "%s:%d: not an Intel hex record\n", path, lineno);
  return -1;
}

static void usage(void) {
  fprintf(stderr, "usage: fsrlab_boot BOOTLOADER.hex --uart-fd N [--flash-out FILE]\n");
  exit(2);
}

int main(int argc, char **argv) {
  const char *hex = NULL, *flash_out = NULL;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--uart-fd") && i + 1 < argc) uart_fd = atoi(argv[++i]);
    else if (!strcmp(a, "--flash-out") && i + 1 < argc) flash_out = argv[++i];
    else if (a[0] != '-' && !hex) hex = a;
    else usage();
  }
  if (!hex || uart_fd < 0) usage();
  signal(SIGPIPE, SIG_IGN);
  dup2(2, 1); /* simavr prints notes with printf */
  fcntl(uart_fd, F_SETFL, fcntl(uart_fd, F_GETFL) | O_NONBLOCK);
  setvbuf(stderr, NULL, _IOLBF, 0);

  avr = avr_make_mcu_by_name("atmega328p");
  if (!avr) { fprintf(stderr, "simavr has no atmega328p\n"); return 2; }
  avr_init(avr);
  avr->frequency = F_CPU_HZ;
  avr->vcc = avr->avcc = avr->aref = 5000;
  avr->log = 0;
  if (load_hex(hex) != 0) return 2;
  avr->reset_pc = BOOT_START; /* BOOTRST: reset jumps to the boot section */
  avr->codeend = avr->flashend;

  uint32_t flags = 0;
  avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
  flags &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP); /* no echo, no usleep */
  avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), uart_out_cb, NULL);
  uart_in = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
  avr_register_io_write(avr, UCSR0A_ADDR, ucsr0a_write, NULL);

  fprintf(stderr, "#READY\n");
  /* held in reset until the host's first byte (the DTR pulse, see above) */
  while (!stdin_eof && ihead == itail) wait_io(100);
  avr_reset(avr);
  avr->data[MCUSR_ADDR] = EXTRF;
  avr->data[UCSR0A_ADDR] |= UDRE0;

  double wall0 = now_s();
  uint64_t cycle0 = avr->cycle, next_tick = avr->cycle, next_feed = avr->cycle + 2 * TICK_CYCLES;
  avr_flashaddr_t last_pc = avr->pc;
  fprintf(stderr, "#RESET %llu %u\n", (unsigned long long)avr->cycle, avr->data[MCUSR_ADDR]);
  int state = cpu_Running;
  while (!stdin_eof) {
    if (avr->cycle >= next_tick) {
      next_tick = avr->cycle + TICK_CYCLES;
      flush_out();
      wait_io(0);
      double ahead; /* never ahead of the wall clock */
      while (!stdin_eof && (ahead = (double)(avr->cycle - cycle0) / F_CPU_HZ - (now_s() - wall0)) > 0.001)
        wait_io((int)(ahead * 1000) + 1);
    }
    /* host bytes at the line's rate; the first ones wait until the bootloader has set up its USART */
    if (ihead != itail && avr->cycle >= next_feed) {
      avr_raise_irq(uart_in, ibuf[ihead % sizeof ibuf]);
      ihead++;
      next_feed = avr->cycle + BYTE_CYCLES;
    }
    state = avr_run(avr);
    if (state == cpu_Done || state == cpu_Crashed) {
      fprintf(stderr, "#STOPPED %d at pc 0x%x\n", state, (unsigned)avr->pc);
      break;
    }
    if (avr->pc == BOOT_START && last_pc != BOOT_START) {
      /* a reset (the watchdog's): simavr cleared the I/O space; UDRE0 is 1 after a reset */
      avr->data[UCSR0A_ADDR] |= UDRE0;
      fprintf(stderr, "#RESET %llu %u\n", (unsigned long long)avr->cycle, avr->data[MCUSR_ADDR]);
      next_feed = avr->cycle + 2 * TICK_CYCLES;
    }
    last_pc = avr->pc;
  }
  flush_out();
  if (flash_out) {
    FILE *f = fopen(flash_out, "wb");
    if (!f || fwrite(avr->flash, 1, avr->flashend + 1, f) != (size_t)avr->flashend + 1) {
      fprintf(stderr, "cannot write %s\n", flash_out);
      return 3;
    }
    fclose(f);
  }
  fprintf(stderr, "#END %llu\n", (unsigned long long)avr->cycle);
  return 0;
}
