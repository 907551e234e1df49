#pragma once
// acquisition-internal: the state behind AravisCamera and the helpers its parts share. Included
// only by the aravis_*.cc files (the one place irdist includes <arv.h>); never by a public header.
// The parts, one job each: aravis_features.cc (reading and writing features, every write checked
// for access mode and lock first; the state found, saved and put back), aravis_setup.cc (pixel
// format, region, analog controls, the neutral pixel pipeline, exposure), aravis_trigger.cc (the
// frame trigger as the SFNC defines it), aravis_stream.cc (packets, stream, buffers, frames),
// aravis_discovery.cc (listing and naming cameras), aravis_configure.cc (the Camera interface:
// open, configure, read back, exposure, describe, put back). No aravis_camera.cc: its header and
// this one would include each other.

#include <arv.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/aravis_camera.h"
#include "acquisition/pixel_pipeline.h"

namespace irdist {

struct GObjectUnref {
  void operator()(gpointer object) const {
    if (object != nullptr) g_object_unref(object);
  }
};
template <typename T>
using GPtr = std::unique_ptr<T, GObjectUnref>;

// Throws a CameraError naming the failed call and the camera when `error` is set (never a source
// path: the message is for the user); frees the GError.
void ThrowOnError(GError* error, const std::string& what, const std::string& camera);
std::string OrEmpty(const char* text);
std::string JoinNames(const std::vector<std::string>& items);
bool LooksLikeIpv4(const std::string& name);
bool IsLoopback(const std::string& address);
// Takes a GigE Vision camera's control channel, or finds it held by this client; throws
// CameraError naming the holder when another has it (aravis_configure.cc). Other transports: none.
void TakeControl(ArvCamera* camera, const std::string& name);

struct AravisCamera::Impl {
  GPtr<ArvCamera> camera;
  GPtr<ArvStream> stream;
  GPtr<ArvChunkParser> chunk_parser;
  CameraIdentity identity;
  CameraSettings settings;
  bool configured = false;
  bool streaming = false;
  bool exposure_chunks = false;
  int payload_bytes = 0;
  int packet_size = 0;
  int bit_depth = 16;
  int warmup_discarded = 0;
  double exposure_min_us = 0.0;
  double exposure_max_us = 0.0;
  std::string exposure_bounds_note;  // where the bounds came from (irdist.ExposureBounds)
  ArvGcFeatureNode* exposure_node = nullptr;  // ExposureTime (or ExposureTimeAbs), found by
                                              // ReadExposureBounds; checked before each write
  std::string pixel_format;
  std::string frame_trigger;  // FrameStart, ExposureStart, or "" (a single trigger)
  std::vector<PixelFeatureState> pixel_pipeline;  // as found and as set, by Configure

  // One writable feature's value as found, under a TriggerSelector entry (or none).
  struct SavedFeature {
    std::string selector;
    std::string feature;
    std::string value;
  };
  std::vector<SavedFeature> found_state;  // saved by the last Configure
  // Enumerations found holding no entry's value, never saved (named when putting back): by the
  // last SaveState, and by the one behind found_state.
  std::vector<std::string> unsaved;
  std::vector<std::string> found_unsaved;

  std::string Name() const { return identity.serial + "@" + identity.address; }
  ArvDevice* Device() const { return arv_camera_get_device(camera.get()); }

  // --- features (aravis_features.cc) ---
  bool Has(const char* feature) const;
  ArvGcFeatureNode* FeatureNode(const char* feature) const;
  // Throws CameraError naming `feature` and the fix when it is absent, read-only or locked now.
  ArvGcFeatureNode* RequireWritable(const char* feature, const std::string& fix) const;
  std::string GetString(const char* feature);
  std::vector<std::string> EnumEntries(const char* feature);
  void SetEnum(const char* feature, const std::string& value, const std::string& fix);
  void SetBoolean(const char* feature, bool value, const std::string& fix);
  void SetFloat(const char* feature, double value, const std::string& fix);
  void AutoOff(const char* feature);
  void CheckFloat(const char* feature, double wanted, double got) const;
  ArvGcFeatureNode* WritableNode(const char* feature) const;
  std::optional<std::string> ValueAsString(ArvGcFeatureNode* node) const;
  void SaveFeature(const std::string& selector, const char* feature,
                   std::vector<SavedFeature>* saved);
  std::vector<SavedFeature> SaveState();
  std::string WriteFeature(const std::string& selector, const char* feature,
                           const std::string& value);
  std::string RestoreState(const std::vector<SavedFeature>& saved,
                           const std::vector<std::string>& skipped_names);

  // --- setup (aravis_setup.cc) ---
  void SetRegion(const CameraSettings& s);
  void ConfigureAnalog(const CameraSettings& s);
  void ConfigureBlackLevel(const CameraSettings& s);
  void ConfigureGamma(const CameraSettings& s);
  void ConfigurePixelPipeline();
  PixelFeatureState SetNeutral(const PixelFeatureSpec& spec, const char* feature, bool write);
  std::string ColourSensor();
  void RefuseRawMosaic();
  void ConfigureChunks();
  void ReadExposureBounds();
  void CrossCheckExposureBounds();
  void CheckExposureRange(double exposure_us) const;
  void WriteExposure(double exposure_us);

  // --- trigger (aravis_trigger.cc) ---
  void SetExposureModeTimed();
  std::string ChooseFrameTrigger(const std::vector<std::string>& offered) const;
  void OtherTriggersOff(const std::string& frame);
  void RequireTriggerControls(const CameraSettings& s, const std::string& what) const;
  void SelectFrameTrigger(const CameraSettings& s);
  void ConfigureFrameRate(const CameraSettings& s);
  void ConfigureTrigger(const CameraSettings& s);

  // --- stream (aravis_stream.cc) ---
  void SetupPacketSize();
  void TuneGvStream(ArvStream* raw_stream);
  bool DeclaresResend();
  void SetupStream();
  static cv::Mat ToMat(ArvBuffer* buffer);
};

}  // namespace irdist
