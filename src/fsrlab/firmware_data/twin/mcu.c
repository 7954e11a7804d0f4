/* The simulated ATmega328P of the harnesses (see mcu.h). */
#include <stdio.h>
#include <string.h>

#include <sim_avr.h>
#include <sim_elf.h>
#include <sim_hex.h>
#include <sim_io.h>
#include <sim_cycle_timers.h>
#include <avr_uart.h>

#include "mcu.h"

avr_t *mcu_load(const char *elf)
{
  elf_firmware_t fw;
  memset(&fw, 0, sizeof fw);
  size_t n = strlen(elf);
  if (n > 4 && !strcmp(elf + n - 4, ".hex")) {
    /* the image as flashed (what the package ships): .text and .data's initial values from 0 */
    fw.flash = read_ihex_file(elf, &fw.flashsize, &fw.flashbase);
    if (!fw.flash || fw.flashbase != 0) { fprintf(stderr, "cannot read %s\n", elf); return NULL; }
  } else if (elf_read_firmware(elf, &fw) != 0) { fprintf(stderr, "cannot read %s\n", elf); return NULL; }
  avr_t *avr = avr_make_mcu_by_name("atmega328p");
  if (!avr) { fprintf(stderr, "simavr has no atmega328p\n"); return NULL; }
  avr_init(avr);
  avr->frequency = 16000000;
  avr_load_firmware(avr, &fw);
  avr->frequency = 16000000; /* the ELF's mmcu section may set it again */
  avr->vcc = avr->avcc = avr->aref = 5000;
  avr->log = 0;
  return avr;
}

/* UDRE0 is read-only and 1 after a reset (datasheet); simavr 1.6 clears it on any write to UCSR0A
 * (the firmware sets U2X0) and only sets it again after a byte was sent, so the first byte would never
 * go. Set it once, 1 ms after reset, when the firmware has set up the USART. */
static avr_cycle_count_t udre_fix_cb(struct avr_t *a, avr_cycle_count_t when, void *param)
{
  (void)when; (void)param;
  a->data[0xC0] |= 0x20; /* UCSR0A.UDRE0 */
  return 0;
}

avr_irq_t *mcu_uart(avr_t *avr, avr_irq_notify_t out_cb)
{
  uint32_t flags = 0;
  avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
  flags &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP); /* no echo, no usleep */
  avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), out_cb, NULL);
  avr_cycle_timer_register(avr, 16000, udre_fix_cb, NULL);
  return avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
}
