#include "visibility/embree_scene.h"

#include <gtest/gtest.h>

#include <string>

namespace facets {
namespace {

bool NativePackets(const EmbreeDevice& device, RTCDeviceProperty property) {
  return rtcGetDeviceProperty(device.get(), property) != 0;
}

// The reported instruction set agrees with the packet widths Embree itself says it runs
// natively: 16-wide with AVX-512, 8-wide with AVX and AVX2, 4-wide below.
void ExpectIsaMatchesNativePackets(const EmbreeDevice& device) {
  const std::string isa = device.KernelIsa();
  EXPECT_EQ(NativePackets(device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED), isa == "AVX-512") << isa;
  EXPECT_EQ(NativePackets(device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED),
            isa == "AVX-512" || isa == "AVX2" || isa == "AVX")
      << isa;
}

TEST(EmbreeDevice, KernelIsaAgreesWithEmbreesNativePacketWidths) {
  const EmbreeDevice native("");
  std::printf("%s\n", native.Describe().c_str());
  ExpectIsaMatchesNativePackets(native);
  const std::string best = native.KernelIsa();
  if (best == "AVX-512" || best == "AVX2") {
    const EmbreeDevice avx2("isa=avx2");
    EXPECT_EQ(avx2.KernelIsa(), "AVX2");
    EXPECT_EQ(avx2.Describe().find("configuration \"isa=avx2\"") != std::string::npos, true) << avx2.Describe();
    ExpectIsaMatchesNativePackets(avx2);
  }
  const EmbreeDevice sse("threads=1,max_isa=sse4.2");
  EXPECT_EQ(sse.KernelIsa(), "SSE4.2");
  ExpectIsaMatchesNativePackets(sse);
}

}  // namespace
}  // namespace facets
