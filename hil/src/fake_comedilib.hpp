#pragma once
// The fake DAQ's stand-in for the comedilib calls of the comedi back-end: the same names,
// signatures and semantics (comedilib.h of comedilib 0.11), on a FakeDaqBoard found by device
// name (see comedi_backend.ipp and fake_daq.hpp).

#include <cstdint>

namespace fullarm::hil::fakedaq_api {

using lsampl_t = unsigned int;
struct comedi_t;  // a handle: the board's registry entry
struct comedi_range {
  double min;
  double max;
  unsigned int unit;
};
inline constexpr int kMaxPolynomialCoefficients = 4;
struct comedi_polynomial_t {
  double coefficients[kMaxPolynomialCoefficients];
  double expansion_origin;
  unsigned order;
};
struct comedi_calibration_t;  // the fake board has no soft calibration: never returned
enum comedi_oor_behavior { COMEDI_OOR_NUMBER = 0, COMEDI_OOR_NAN };
enum comedi_conversion_direction { COMEDI_TO_PHYSICAL, COMEDI_FROM_PHYSICAL };

inline constexpr int kSubdeviceAnalogInput = 1;   // COMEDI_SUBD_AI
inline constexpr int kSubdeviceAnalogOutput = 2;  // COMEDI_SUBD_AO
inline constexpr int kSubdeviceDigitalIo = 5;     // COMEDI_SUBD_DIO
inline constexpr unsigned kArefGround = 0;        // AREF_GROUND
inline constexpr unsigned kDigitalOutput = 1;     // COMEDI_OUTPUT
inline constexpr comedi_oor_behavior kOutOfRangeNan = COMEDI_OOR_NAN;
inline constexpr comedi_conversion_direction kToPhysical = COMEDI_TO_PHYSICAL;

comedi_t* comedi_open(const char* filename);
int comedi_close(comedi_t* device);
int comedi_errno();
const char* comedi_strerror(int error);
int comedi_find_subdevice_by_type(comedi_t* device, int type, unsigned int start_subdevice);
int comedi_get_n_channels(comedi_t* device, unsigned int subdevice);
lsampl_t comedi_get_maxdata(comedi_t* device, unsigned int subdevice, unsigned int channel);
comedi_range* comedi_get_range(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int range);
int comedi_data_read(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int range, unsigned int aref,
                     lsampl_t* data);
int comedi_data_write(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int range,
                      unsigned int aref, lsampl_t data);
int comedi_dio_config(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int direction);
int comedi_dio_write(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int bit);
double comedi_to_phys(lsampl_t data, const comedi_range* range, lsampl_t maxdata);
lsampl_t comedi_from_phys(double data, const comedi_range* range, lsampl_t maxdata);
comedi_oor_behavior comedi_set_global_oor_behavior(comedi_oor_behavior behavior);
comedi_calibration_t* comedi_parse_calibration_file(const char* file);
void comedi_cleanup_calibration(comedi_calibration_t* calibration);
int comedi_get_softcal_converter(unsigned subdevice, unsigned channel, unsigned range,
                                 comedi_conversion_direction direction, const comedi_calibration_t* calibration,
                                 comedi_polynomial_t* polynomial);
double comedi_to_physical(lsampl_t data, const comedi_polynomial_t* polynomial);

}  // namespace fullarm::hil::fakedaq_api
