!> Working precision for all of flexmor.
module core_kinds
  use, intrinsic :: iso_fortran_env, only: real64, int64
  implicit none
  private
  public :: wp, i8

  integer, parameter :: wp = real64
  integer, parameter :: i8 = int64
end module core_kinds
