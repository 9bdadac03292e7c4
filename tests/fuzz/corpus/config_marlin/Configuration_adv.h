/**
 * Marlin 3D Printer Firmware
 * Copyright (c) 2025 MarlinFirmware [https://github.com/MarlinFirmware/Marlin]
 *
 * This program is free software: you can redistribute it and/or modify
 * it under the terms of the GNU General Public License as published by
 * the Free Software Foundation, either version 3 of the License, or
 * (at your option) any later version.
 */
#pragma once

/**
 * Configuration_adv.h
 *
 * Advanced settings (an abridged file for tests: only the sections tunekit edits and
 * their neighbours are kept, in the layout of Marlin 2.1.x).
 */
#define CONFIGURATION_ADV_H_VERSION 02010300

// @section temperature

#if ENABLED(THERMAL_PROTECTION_HOTENDS)
  #define THERMAL_PROTECTION_PERIOD        40 // (seconds)
  #define THERMAL_PROTECTION_HYSTERESIS     4 // (°C)
#endif

// @section motion

/**
 * Input Shaping
 *
 * Zero Vibration (ZV) input shaping for X and/or Y movements.
 * Tune at runtime with M593 D<zeta> F<frequency> [X] [Y].
 */
//#define INPUT_SHAPING_X
//#define INPUT_SHAPING_Y
#if ANY(INPUT_SHAPING_X, INPUT_SHAPING_Y)
  #if ENABLED(INPUT_SHAPING_X)
    #define SHAPING_FREQ_X  40          // (Hz) The default dominant resonant frequency on the X axis.
    #define SHAPING_ZETA_X  0.15f       // Damping ratio of the X axis (range: 0.0 = no damping to 1.0 = critical damping).
  #endif
  #if ENABLED(INPUT_SHAPING_Y)
    #define SHAPING_FREQ_Y  40          // (Hz) The default dominant resonant frequency on the Y axis.
    #define SHAPING_ZETA_Y  0.15f       // Damping ratio of the Y axis (range: 0.0 = no damping to 1.0 = critical damping).
  #endif
  //#define SHAPING_MIN_FREQ  20        // (Hz) By default the minimum of the shaping frequencies.
  //#define SHAPING_MENU                // Add a menu to the LCD to set shaping parameters.
#endif

#define AXIS_RELATIVE_MODES { false, false, false, false }

// @section extruder

/**
 * Linear Pressure Control v1.5
 *
 * Assumption: advance [steps] = k * (delta velocity [steps/s])
 * K=0 means advance disabled.
 *
 * Set K with M900 K<value> (mm of filament compression per 1 mm/s of extruder speed).
 */
//#define LIN_ADVANCE
#if ENABLED(LIN_ADVANCE)
  #if ENABLED(DISTINCT_E_FACTORS)
    #define ADVANCE_K { 0.22 }    // (mm) Compression length per 1mm/s extruder speed, per extruder
  #else
    #define ADVANCE_K 0.22        // (mm) Compression length applying to all extruders
  #endif
  //#define ADVANCE_K_EXTRA       // Add a second linear advance constant, configurable with M900 L.
  //#define LA_DEBUG              // Print debug information to serial during operation.
  //#define SMOOTH_LIN_ADVANCE    // Smooth the extruder speed to reduce the extruder acceleration
  #if ENABLED(SMOOTH_LIN_ADVANCE)
    #define ADVANCE_TAU 0.02      // (s) Smoothing time; M900 U<tau>
  #endif
#endif

// @section leveling

#if ANY(MESH_BED_LEVELING, AUTO_BED_LEVELING_UBL)
  #define MESH_INSET 10          // Set Mesh bounds as an inset region of the bed
#endif
