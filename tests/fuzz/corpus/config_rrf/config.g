; Configuration file for Duet 3 Mini 5+ (firmware version 3.5)
; executed by the firmware on start-up

; General preferences
G90                                          ; send absolute coordinates...
M83                                          ; ...but relative extruder moves
M550 P"Bench printer"                        ; set printer name

; Drives
M569 P0.0 S1                                 ; physical drive 0.0 goes forwards
M569 P0.1 S1                                 ; physical drive 0.1 goes forwards
M569 P0.2 S1                                 ; physical drive 0.2 goes forwards
M569 P0.3 S0                                 ; physical drive 0.3 goes backwards
M584 X0.0 Y0.1 Z0.2 E0.3                     ; set drive mapping
M350 X16 Y16 Z16 E16 I1                      ; configure microstepping with interpolation
M92 X80.00 Y80.00 Z400.00 E420.00            ; set steps per mm
M566 X900.00 Y900.00 Z60.00 E120.00          ; set maximum instantaneous speed changes (mm/min)
M203 X18000.00 Y18000.00 Z900.00 E3600.00    ; set maximum speeds (mm/min)
M201 X3000.00 Y3000.00 Z200.00 E5000.00      ; set accelerations (mm/s^2)
M906 X800 Y800 Z800 E600 I30                 ; set motor currents (mA) and motor idle factor in per cent
M84 S30                                      ; set idle timeout
M572 D0 S0.05                                ; pressure advance (s)

; Axis Limits
M208 X0 Y0 Z0 S1                             ; set axis minima
M208 X220 Y220 Z250 S0                       ; set axis maxima

; Endstops
M574 X1 S1 P"io0.in"                         ; configure switch-type endstop for low end on X
M574 Y1 S1 P"io1.in"                         ; configure switch-type endstop for low end on Y

; Heaters
M308 S0 P"temp0" Y"thermistor" T100000 B4138 ; configure sensor 0 as thermistor on pin temp0
M950 H0 C"out0" T0                           ; create bed heater output on out0 and map it to sensor 0
M140 H0                                      ; map heated bed to heater 0

; Tools
M563 P0 D0 H1 F0                             ; define tool 0
G10 P0 X0 Y0 Z0                              ; set tool 0 axis offsets
G10 P0 R0 S0                                 ; set initial tool 0 active and standby temperatures to 0C

; Miscellaneous
M501                                         ; load saved parameters from non-volatile memory
T0                                           ; select first tool
