// SPDX-License-Identifier: Apache-2.0
#include "workers/capture/aravis_camera.h"

#include <arv.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace vb::capture {
namespace {

// PFNC names, as GenICam PixelFormat enumeration entries.
const char* PfncName(PixelFormat format) {
  switch (format) {
    case PixelFormat::kRgb8: return "RGB8";
    case PixelFormat::kMono8: return "Mono8";
    case PixelFormat::kBayerRg8: return "BayerRG8";
    case PixelFormat::kBayerGb8: return "BayerGB8";
    case PixelFormat::kBayerGr8: return "BayerGR8";
    case PixelFormat::kBayerBg8: return "BayerBG8";
  }
  return "?";
}

bool FromPfnc(ArvPixelFormat pfnc, PixelFormat* format) {
  switch (pfnc) {
    case ARV_PIXEL_FORMAT_RGB_8_PACKED: *format = PixelFormat::kRgb8; return true;
    case ARV_PIXEL_FORMAT_MONO_8: *format = PixelFormat::kMono8; return true;
    case ARV_PIXEL_FORMAT_BAYER_RG_8: *format = PixelFormat::kBayerRg8; return true;
    case ARV_PIXEL_FORMAT_BAYER_GB_8: *format = PixelFormat::kBayerGb8; return true;
    case ARV_PIXEL_FORMAT_BAYER_GR_8: *format = PixelFormat::kBayerGr8; return true;
    case ARV_PIXEL_FORMAT_BAYER_BG_8: *format = PixelFormat::kBayerBg8; return true;
    default: return false;
  }
}

const char* BufferStatusName(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_UNKNOWN: return "UNKNOWN";
    case ARV_BUFFER_STATUS_SUCCESS: return "SUCCESS";
    case ARV_BUFFER_STATUS_CLEARED: return "CLEARED";
    case ARV_BUFFER_STATUS_TIMEOUT: return "TIMEOUT";
    case ARV_BUFFER_STATUS_MISSING_PACKETS: return "MISSING_PACKETS";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID: return "WRONG_PACKET_ID";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH: return "SIZE_MISMATCH";
    case ARV_BUFFER_STATUS_FILLING: return "FILLING";
    case ARV_BUFFER_STATUS_ABORTED: return "ABORTED";
  }
  return "UNRECOGNISED";
}

// Device errors that mean the control channel no longer answers.
bool IsConnectionLoss(const GError* error) {
  return error->domain == ARV_DEVICE_ERROR &&
         (error->code == ARV_DEVICE_ERROR_TIMEOUT || error->code == ARV_DEVICE_ERROR_NOT_CONNECTED ||
          error->code == ARV_DEVICE_ERROR_TRANSFER_ERROR);
}

// Owns a GError* filled by an Aravis call.
class GErrorHolder {
 public:
  GErrorHolder() = default;
  ~GErrorHolder() { g_clear_error(&error_); }
  GErrorHolder(const GErrorHolder&) = delete;
  GErrorHolder& operator=(const GErrorHolder&) = delete;
  GError** out() {
    g_clear_error(&error_);
    return &error_;
  }
  explicit operator bool() const { return error_ != nullptr; }
  const GError* get() const { return error_; }
  std::string message() const { return error_ != nullptr ? error_->message : ""; }

 private:
  GError* error_ = nullptr;
};

// Frees a NULL-terminated-or-counted array returned by arv_camera_dup_*_as_strings (the strings
// themselves belong to the genicam tree; only the array is ours).
std::vector<std::string> TakeStrings(const char** strings, guint n) {
  std::vector<std::string> out;
  if (strings == nullptr) return out;
  for (guint i = 0; i < n; ++i) out.emplace_back(strings[i] != nullptr ? strings[i] : "");
  g_free(static_cast<gpointer>(strings));
  return out;
}

}  // namespace

absl::Status AravisCameraOptions::Validate() const {
  if (hardware_trigger_source.empty()) {
    return absl::InvalidArgumentError("hardware_trigger_source: must not be empty");
  }
  if (n_buffers < 1 || n_buffers > 64) {
    return absl::InvalidArgumentError(
        absl::StrCat("n_buffers: ", n_buffers, " is outside [1, 64]"));
  }
  return absl::OkStatus();
}

struct AravisCamera::Impl {
  AravisCameraOptions options;
  ArvCamera* camera = nullptr;
  ArvStream* stream = nullptr;
  gulong control_lost_handler = 0;
  // Set by Aravis' heartbeat thread (control-lost signal) or by us after a control timeout.
  std::atomic<bool> lost{false};
  bool configured = false;
  CameraSettings settings;

  static void OnControlLost(ArvDevice* /*device*/, gpointer user_data) {
    static_cast<Impl*>(user_data)->lost.store(true);
  }
};

AravisCamera::AravisCamera(std::string rig_name, std::string device_id,
                           AravisCameraOptions options)
    : name_(std::move(rig_name)), device_id_(std::move(device_id)), impl_(new Impl) {
  impl_->options = std::move(options);
}

AravisCamera::~AravisCamera() { Close(); }

namespace {

std::string Who(const std::string& name, const std::string& device_id) {
  return absl::StrCat("camera ", name, " (device '", device_id, "')");
}

}  // namespace

absl::Status AravisCamera::Open() {
  if (impl_->camera != nullptr) return absl::OkStatus();
  if (absl::Status s = impl_->options.Validate(); !s.ok()) return s;
  GErrorHolder error;
  ArvCamera* camera = arv_camera_new(device_id_.c_str(), error.out());
  if (camera == nullptr || error) {
    if (camera != nullptr) g_object_unref(camera);
    const bool not_found = error && error.get()->domain == ARV_DEVICE_ERROR &&
                           error.get()->code == ARV_DEVICE_ERROR_NOT_FOUND;
    std::string message =
        absl::StrCat(Who(name_, device_id_), ": cannot open: ",
                     error ? error.message() : std::string("arv_camera_new returned no camera"));
    return not_found ? absl::NotFoundError(message) : absl::UnavailableError(message);
  }
  impl_->camera = camera;
  impl_->lost.store(false);
  impl_->configured = false;
  impl_->control_lost_handler =
      g_signal_connect(arv_camera_get_device(camera), "control-lost",
                       G_CALLBACK(&Impl::OnControlLost), impl_.get());
  return absl::OkStatus();
}

namespace {

// Status for a failed Aravis call: connection loss -> UNAVAILABLE, else `code`.
absl::Status FromGError(const GErrorHolder& error, absl::StatusCode code,
                        std::string_view context) {
  if (IsConnectionLoss(error.get())) {
    return absl::UnavailableError(absl::StrCat(std::string(context), ": ", error.message()));
  }
  return absl::Status(code, absl::StrCat(std::string(context), ": ", error.message()));
}

}  // namespace

absl::Status AravisCamera::Configure(const CameraSettings& settings) {
  if (impl_->camera == nullptr) {
    return absl::FailedPreconditionError(absl::StrCat(Who(name_, device_id_), ": not open"));
  }
  if (impl_->stream != nullptr) {
    return absl::FailedPreconditionError(
        absl::StrCat(Who(name_, device_id_), ": Configure while acquiring"));
  }
  if (impl_->lost.load()) {
    return absl::UnavailableError(absl::StrCat(Who(name_, device_id_), ": device lost"));
  }
  if (absl::Status s = settings.Validate(); !s.ok()) return s;
  ArvCamera* cam = impl_->camera;
  const std::string who = Who(name_, device_id_);
  GErrorHolder error;
  auto fail = [&](absl::StatusCode code, std::string_view what) {
    absl::Status s = FromGError(error, code, absl::StrCat(who, ": ", std::string(what)));
    if (absl::IsUnavailable(s)) impl_->lost.store(true);
    return s;
  };
  impl_->configured = false;

  // Pixel format: checked against the enumeration's available entries, so that a format the
  // device lacks is INVALID_ARGUMENT rather than a GenICam error string.
  {
    guint n = 0;
    const char** raw = arv_camera_dup_available_pixel_formats_as_strings(cam, &n, error.out());
    if (error) return fail(absl::StatusCode::kInternal, "reading PixelFormat entries");
    const std::vector<std::string> available = TakeStrings(raw, n);
    const char* wanted = PfncName(settings.pixel_format);
    if (std::find(available.begin(), available.end(), wanted) == available.end()) {
      return absl::InvalidArgumentError(absl::StrCat(
          "pixel_format: ", who, " does not support ",
          std::string(PixelFormatName(settings.pixel_format)), " (PFNC ", wanted,
          "); it offers ", absl::StrJoin(available, ", ")));
    }
    arv_camera_set_pixel_format_from_string(cam, wanted, error.out());
    if (error) return fail(absl::StatusCode::kInvalidArgument, "pixel_format: setting it failed");
    const char* now = arv_camera_get_pixel_format_as_string(cam, error.out());
    if (error) return fail(absl::StatusCode::kInternal, "reading back PixelFormat");
    if (now == nullptr || std::strcmp(now, wanted) != 0) {
      return absl::InvalidArgumentError(absl::StrCat("pixel_format: ", who, " kept ",
                                                     now ? now : "(none)", " instead of ", wanted));
    }
  }

  // Exposure, in microseconds (SFNC ExposureTime or the older ExposureTimeAbs).
  {
    const gboolean available = arv_camera_is_exposure_time_available(cam, error.out());
    if (error) return fail(absl::StatusCode::kInternal, "checking exposure feature");
    if (!available) {
      return absl::InvalidArgumentError(
          absl::StrCat("exposure_us: ", who, " has no exposure time control"));
    }
    double min_us = 0, max_us = 0;
    arv_camera_get_exposure_time_bounds(cam, &min_us, &max_us, error.out());
    if (error) return fail(absl::StatusCode::kInternal, "reading exposure bounds");
    if (settings.exposure_us < min_us || settings.exposure_us > max_us) {
      return absl::InvalidArgumentError(absl::StrCat("exposure_us: ", settings.exposure_us,
                                                     " is outside the range of ", who, " [",
                                                     min_us, ", ", max_us, "]"));
    }
    arv_camera_set_exposure_time(cam, settings.exposure_us, error.out());
    if (error) return fail(absl::StatusCode::kInvalidArgument, "exposure_us: setting it failed");
  }

  // Gain. Without a gain feature only the neutral 0 is accepted.
  {
    const gboolean available = arv_camera_is_gain_available(cam, error.out());
    if (error) return fail(absl::StatusCode::kInternal, "checking gain feature");
    if (!available) {
      if (settings.gain_db != 0.0) {
        return absl::InvalidArgumentError(
            absl::StrCat("gain_db: ", who, " has no gain control (only 0 is accepted)"));
      }
    } else {
      double min_gain = 0, max_gain = 0;
      arv_camera_get_gain_bounds(cam, &min_gain, &max_gain, error.out());
      if (error) return fail(absl::StatusCode::kInternal, "reading gain bounds");
      if (settings.gain_db < min_gain || settings.gain_db > max_gain) {
        return absl::InvalidArgumentError(absl::StrCat("gain_db: ", settings.gain_db,
                                                       " is outside the range of ", who, " [",
                                                       min_gain, ", ", max_gain, "]"));
      }
      arv_camera_set_gain(cam, settings.gain_db, error.out());
      if (error) return fail(absl::StatusCode::kInvalidArgument, "gain_db: setting it failed");
    }
  }

  arv_camera_set_acquisition_mode(cam, ARV_ACQUISITION_MODE_CONTINUOUS, error.out());
  if (error) return fail(absl::StatusCode::kInternal, "setting AcquisitionMode Continuous");

  // Trigger.
  if (settings.trigger == TriggerMode::kFreeRunning) {
    arv_camera_clear_triggers(cam, error.out());
    if (error) return fail(absl::StatusCode::kInvalidArgument, "trigger: clearing triggers");
  } else {
    const std::string source = settings.trigger == TriggerMode::kSoftware
                                   ? std::string("Software")
                                   : impl_->options.hardware_trigger_source;
    guint n = 0;
    const char** raw = arv_camera_dup_available_trigger_sources(cam, &n, error.out());
    if (error) return fail(absl::StatusCode::kInvalidArgument, "trigger: reading TriggerSource");
    const std::vector<std::string> sources = TakeStrings(raw, n);
    if (std::find(sources.begin(), sources.end(), source) == sources.end()) {
      return absl::InvalidArgumentError(absl::StrCat("trigger: ", who,
                                                     " has no trigger source ", source,
                                                     " (it offers ", absl::StrJoin(sources, ", "),
                                                     ")"));
    }
    arv_camera_set_trigger(cam, source.c_str(), error.out());
    if (error) return fail(absl::StatusCode::kInvalidArgument, "trigger: setting it failed");
  }

  impl_->settings = settings;
  impl_->configured = true;
  return absl::OkStatus();
}

absl::Status AravisCamera::StartAcquisition() {
  const std::string who = Who(name_, device_id_);
  if (impl_->camera == nullptr) return absl::FailedPreconditionError(who + ": not open");
  if (impl_->stream != nullptr) return absl::FailedPreconditionError(who + ": already acquiring");
  if (!impl_->configured) {
    return absl::FailedPreconditionError(who + ": Configure before StartAcquisition");
  }
  if (impl_->lost.load()) return absl::UnavailableError(who + ": device lost");
  ArvCamera* cam = impl_->camera;
  GErrorHolder error;
  auto fail = [&](std::string_view what) {
    absl::Status s = FromGError(error, absl::StatusCode::kInternal,
                                absl::StrCat(who, ": ", std::string(what)));
    if (absl::IsUnavailable(s)) impl_->lost.store(true);
    return s;
  };
  const guint payload = arv_camera_get_payload(cam, error.out());
  if (error) return fail("reading PayloadSize");
  if (payload == 0) return absl::InternalError(who + ": PayloadSize is 0");
  ArvStream* stream = arv_camera_create_stream(cam, nullptr, nullptr, error.out());
  if (error || stream == nullptr) {
    if (stream != nullptr) g_object_unref(stream);
    if (!error) return absl::InternalError(who + ": cannot create stream");
    return fail("creating stream");
  }
  for (int i = 0; i < impl_->options.n_buffers; ++i) {
    arv_stream_push_buffer(stream, arv_buffer_new_allocate(payload));
  }
  arv_camera_start_acquisition(cam, error.out());
  if (error) {
    g_object_unref(stream);
    return fail("starting acquisition");
  }
  impl_->stream = stream;
  return absl::OkStatus();
}

absl::Status AravisCamera::Trigger() {
  const std::string who = Who(name_, device_id_);
  if (impl_->stream == nullptr) return absl::FailedPreconditionError(who + ": not acquiring");
  if (impl_->lost.load()) return absl::UnavailableError(who + ": device lost");
  if (impl_->settings.trigger != TriggerMode::kSoftware) return absl::OkStatus();
  GErrorHolder error;
  arv_camera_software_trigger(impl_->camera, error.out());
  if (error) {
    absl::Status s = FromGError(error, absl::StatusCode::kInternal, who + ": software trigger");
    if (absl::IsUnavailable(s)) impl_->lost.store(true);
    return s;
  }
  return absl::OkStatus();
}

absl::StatusOr<Frame> AravisCamera::Retrieve(absl::Duration timeout) {
  const std::string who = Who(name_, device_id_);
  if (impl_->stream == nullptr) return absl::FailedPreconditionError(who + ": not acquiring");
  if (impl_->lost.load()) return absl::UnavailableError(who + ": device lost");
  const int64_t timeout_us = std::max<int64_t>(0, absl::ToInt64Microseconds(timeout));
  ArvBuffer* buffer =
      arv_stream_timeout_pop_buffer(impl_->stream, static_cast<guint64>(timeout_us));
  if (buffer == nullptr) {
    if (impl_->lost.load()) return absl::UnavailableError(who + ": device lost");
    return absl::DeadlineExceededError(
        absl::StrCat(who, ": no frame within ", absl::FormatDuration(timeout)));
  }
  // Every path below re-queues the buffer.
  struct Requeue {
    ArvStream* stream;
    ArvBuffer* buffer;
    ~Requeue() { arv_stream_push_buffer(stream, buffer); }
  } requeue{impl_->stream, buffer};

  const ArvBufferStatus status = arv_buffer_get_status(buffer);
  if (status != ARV_BUFFER_STATUS_SUCCESS) {
    return absl::DataLossError(absl::StrCat(who, ": incomplete frame (buffer status ",
                                            BufferStatusName(status), ", frame id ",
                                            arv_buffer_get_frame_id(buffer), ")"));
  }
  if (arv_buffer_get_payload_type(buffer) != ARV_BUFFER_PAYLOAD_TYPE_IMAGE) {
    return absl::UnimplementedError(absl::StrCat(who, ": payload type ",
                                                 static_cast<int>(arv_buffer_get_payload_type(buffer)),
                                                 " is not a plain image"));
  }
  const ArvPixelFormat pfnc = arv_buffer_get_image_pixel_format(buffer);
  Frame frame;
  frame.camera_name = name_;
  PixelFormat format;
  if (!FromPfnc(pfnc, &format)) {
    return absl::DataLossError(absl::StrCat(who, ": frame has unsupported pixel format 0x",
                                            absl::Hex(static_cast<uint32_t>(pfnc))));
  }
  const int width = arv_buffer_get_image_width(buffer);
  const int height = arv_buffer_get_image_height(buffer);
  if (width <= 0 || height <= 0) {
    return absl::DataLossError(
        absl::StrCat(who, ": frame has invalid size ", width, "x", height));
  }
  gint x_padding = 0, y_padding = 0;
  arv_buffer_get_image_padding(buffer, &x_padding, &y_padding);
  size_t size = 0;
  const auto* data = static_cast<const uint8_t*>(arv_buffer_get_image_data(buffer, &size));
  const size_t row_bytes = static_cast<size_t>(width) * ChannelCount(format);
  const size_t stride = row_bytes + static_cast<size_t>(std::max(0, x_padding));
  if (data == nullptr || size < stride * (height - 1) + row_bytes) {
    return absl::DataLossError(absl::StrCat(who, ": frame holds ", size, " bytes, ", width, "x",
                                            height, " ", std::string(PixelFormatName(format)),
                                            " needs ", stride * (height - 1) + row_bytes));
  }
  frame.image = Image(width, height, format);
  for (int y = 0; y < height; ++y) {
    std::memcpy(frame.image.data.data() + y * row_bytes, data + y * stride, row_bytes);
  }
  const guint64 device_ns = arv_buffer_get_timestamp(buffer);
  frame.timestamp_ns = static_cast<int64_t>(device_ns != 0 ? device_ns
                                                           : arv_buffer_get_system_timestamp(buffer));
  frame.frame_id = arv_buffer_get_frame_id(buffer);
  return frame;
}

absl::Status AravisCamera::StopAcquisition() {
  if (impl_->stream == nullptr) return absl::OkStatus();
  absl::Status result;
  if (!impl_->lost.load()) {
    GErrorHolder error;
    arv_camera_stop_acquisition(impl_->camera, error.out());
    if (error) {
      result = FromGError(error, absl::StatusCode::kInternal,
                          Who(name_, device_id_) + ": stopping acquisition");
      if (absl::IsUnavailable(result)) impl_->lost.store(true);
    }
  }
  // Joins the stream thread; buffers are freed with the stream.
  g_object_unref(impl_->stream);
  impl_->stream = nullptr;
  return result;
}

void AravisCamera::Close() {
  if (impl_ == nullptr || impl_->camera == nullptr) return;
  (void)StopAcquisition();
  ArvDevice* device = arv_camera_get_device(impl_->camera);
  if (impl_->control_lost_handler != 0 && device != nullptr) {
    g_signal_handler_disconnect(device, impl_->control_lost_handler);
  }
  impl_->control_lost_handler = 0;
  g_object_unref(impl_->camera);
  impl_->camera = nullptr;
  impl_->configured = false;
}

std::unique_ptr<Camera> MakeAravisCamera(std::string rig_name, std::string device_id,
                                         AravisCameraOptions options) {
  return std::make_unique<AravisCamera>(std::move(rig_name), std::move(device_id),
                                        std::move(options));
}

}  // namespace vb::capture
