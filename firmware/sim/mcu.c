/* The simulated ATmega328P of the harnesses (see mcu.h). */
#include <stdio.h>
#include <string.h>

#include <sim_avr.h>
#include <sim_elf.h>

#include "mcu.h"

avr_t *mcu_load(const char *elf)
{
  elf_firmware_t fw;
  memset(&fw, 0, sizeof fw);
  if (elf_read_firmware(elf, &fw) != 0) { fprintf(stderr, "cannot read %s\n", elf); return NULL; }
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
