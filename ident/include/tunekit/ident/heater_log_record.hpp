#pragma once
// A firmware's heater log (formats/heater_log.hpp: klippy.log Stats lines, Marlin's temperature
// reports) as a thermal record for the thermal fit. Such logs state the heater's temperature,
// target and PWM only: the record's fan duty and feed are left empty (zero throughout, which the
// fit must take as an assumption: the part fan's speed is not in klippy.log's Stats lines).

#include "tunekit/formats/heater_log.hpp"
#include "tunekit/ident/thermal_record.hpp"

namespace tunekit::ident {

/// The samples of `run` of `log` as a record (times from the run's first sample, so t_s starts
/// at 0). InputError for an empty run or one outside the log.
ThermalRecord thermal_record_from_heater_log(const formats::HeaterLog& log, const formats::HeaterRun& run);

/// The run to fit when none is named: the longest run in which the heater's target is set
/// (above 0) at some sample; InputError when the heater was never given a target.
formats::HeaterRun heated_run(const formats::HeaterLog& log);

}  // namespace tunekit::ident
