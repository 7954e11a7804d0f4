/*
 * The simulated MCU shared by the simavr harnesses (fsrlab_sim.c, fsrlab_twin.c): an ATmega328P at
 * 16 MHz, 5 V supply and reference, the firmware loaded from its ELF, simavr's own log off.
 */
#ifndef FSRLAB_MCU_H
#define FSRLAB_MCU_H

#include <sim_avr.h>

/* The MCU running `elf`, or NULL after one line on stderr saying why. */
avr_t *mcu_load(const char *elf);

#endif
