#pragma once
// The comedilib calls of the comedi back-end, from comedilib itself (see comedi_backend.ipp).

#include <comedilib.h>

namespace fullarm::hil::comedi_real_api {

using ::comedi_calibration_t;
using ::comedi_cleanup_calibration;
using ::comedi_close;
using ::comedi_data_read;
using ::comedi_data_write;
using ::comedi_dio_config;
using ::comedi_dio_write;
using ::comedi_errno;
using ::comedi_find_subdevice_by_type;
using ::comedi_from_phys;
using ::comedi_get_maxdata;
using ::comedi_get_n_channels;
using ::comedi_get_range;
using ::comedi_get_softcal_converter;
using ::comedi_open;
using ::comedi_parse_calibration_file;
using ::comedi_polynomial_t;
using ::comedi_range;
using ::comedi_set_global_oor_behavior;
using ::comedi_strerror;
using ::comedi_t;
using ::comedi_to_phys;
using ::comedi_to_physical;
using ::lsampl_t;

inline constexpr int kSubdeviceAnalogInput = COMEDI_SUBD_AI;
inline constexpr int kSubdeviceAnalogOutput = COMEDI_SUBD_AO;
inline constexpr int kSubdeviceDigitalIo = COMEDI_SUBD_DIO;
inline constexpr unsigned kArefGround = AREF_GROUND;
inline constexpr unsigned kDigitalOutput = COMEDI_OUTPUT;
inline constexpr auto kOutOfRangeNan = COMEDI_OOR_NAN;
inline constexpr auto kToPhysical = COMEDI_TO_PHYSICAL;

}  // namespace fullarm::hil::comedi_real_api
