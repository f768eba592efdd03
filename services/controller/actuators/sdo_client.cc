#include "services/controller/actuators/sdo_client.h"

#include <cstdio>

#include "libs/actuation/canopen.h"
#include "runtime/devices/device_clock.h"

namespace shapesense {
namespace {

using canopen::SdoMessage;

std::string ObjectName(uint16_t index, uint8_t subindex) {
  char text[16];
  std::snprintf(text, sizeof(text), "%04X:%02X", index, subindex);
  return text;
}

}  // namespace

struct SdoClient::Answer {
  SdoMessage message;
};

SdoClient::SdoClient(CanBus& bus, std::chrono::microseconds timeout, FrameHandler other_frames)
    : bus_(bus), timeout_(timeout), other_frames_(std::move(other_frames)) {}

SdoClient::Answer SdoClient::Transfer(int node, const CanFrame& request, uint16_t index,
                                      uint8_t subindex, const std::string& what) {
  bus_.Send(request);
  const uint32_t answer_id = canopen::kSdoResponseBase + static_cast<uint32_t>(node);
  const int64_t deadline_us = SteadyMicros() + timeout_.count();
  for (int64_t left = timeout_.count(); left > 0; left = deadline_us - SteadyMicros()) {
    const std::optional<CanFrame> frame = bus_.Receive(std::chrono::microseconds(left));
    if (!frame) break;
    if (frame->id != answer_id) {
      if (other_frames_) other_frames_(*frame);
      continue;
    }
    const SdoMessage answer = canopen::ParseSdoResponse(*frame);
    if (answer.index != index || answer.subindex != subindex) continue;  // a late answer
    if (answer.kind == SdoMessage::Kind::kAbort) {
      throw SdoError(what + " aborted: " + canopen::SdoAbortText(answer.value), answer.value);
    }
    if (answer.kind == SdoMessage::Kind::kUnsupported) {
      throw SdoError(what +
                         ": the drive answered with a segmented transfer (only objects of up "
                         "to 4 bytes are supported)",
                     0);
    }
    return {answer};
  }
  ++timeouts_;
  // Tell the drive to forget the transfer, as CiA 301 asks of a client that gives up.
  const SdoMessage abort{SdoMessage::Kind::kAbort, index, subindex, canopen::sdo_abort::kTimeout,
                         4};
  bus_.Send(canopen::SdoFrame(canopen::kSdoRequestBase + static_cast<uint32_t>(node), abort));
  throw SdoError(
      what + ": no answer within " + std::to_string(timeout_.count() / 1000) + " ms (SDO timeout)",
      0);
}

uint32_t SdoClient::Upload(int node, uint16_t index, uint8_t subindex) {
  const std::string what =
      "node " + std::to_string(node) + ": SDO read " + ObjectName(index, subindex);
  const SdoMessage request{SdoMessage::Kind::kUploadRequest, index, subindex, 0, 0};
  const Answer answer = Transfer(
      node, canopen::SdoFrame(canopen::kSdoRequestBase + static_cast<uint32_t>(node), request),
      index, subindex, what);
  if (answer.message.kind != SdoMessage::Kind::kUploadResponse) {
    throw SdoError(what + ": the drive answered with a write confirmation", 0);
  }
  return answer.message.value;
}

void SdoClient::Download(int node, uint16_t index, uint8_t subindex, uint32_t value, uint8_t size) {
  const std::string what = "node " + std::to_string(node) + ": SDO write " +
                           ObjectName(index, subindex) + " = " + std::to_string(value);
  const SdoMessage request{SdoMessage::Kind::kDownloadRequest, index, subindex, value, size};
  const Answer answer = Transfer(
      node, canopen::SdoFrame(canopen::kSdoRequestBase + static_cast<uint32_t>(node), request),
      index, subindex, what);
  if (answer.message.kind != SdoMessage::Kind::kDownloadResponse) {
    throw SdoError(what + ": the drive answered with a read response", 0);
  }
}

}  // namespace shapesense
